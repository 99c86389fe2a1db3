"""Read the instruments into the task state: the working tip's pose and velocity, its target, its contacts."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..model.compiler import CompiledTask
from ..terms.state import TaskState
from ..terms.vec import dot, mat_quat, norm

TOOL_SCALE = 0.02  # metres of tip-to-target distance per unit of the tool potential


class ToolSensor:
    """Fills the tool fields of a TaskState from MjData; the first instrument is the working one."""

    def __init__(self, task: CompiledTask):
        self.task = task
        self.tool = task.instruments[0]
        self.tips = {t.tip_geom for t in task.instruments}
        self.scope_tip = task.tip_geom
        self.touch = self.tool.spec.touch
        self.target_radius = task.targets.size
        self.half_fov = math.radians(0.5 * task.spec.scope.fov_deg)

    def read(self, s: TaskState, model: mujoco.MjModel, data: mujoco.MjData, first: bool) -> None:
        """Update the tool's tip pose, velocity, contacts and target errors (positions current)."""
        b = self.tool.tip_body
        pos = tuple(data.xpos[b].tolist())
        if first:
            s.tool_vel = (0.0, 0.0, 0.0)
        else:
            k, p0 = 1.0 / s.dt, s.tool_pos
            s.tool_vel = ((pos[0] - p0[0]) * k, (pos[1] - p0[1]) * k, (pos[2] - p0[2]) * k)
        s.tool_pos, s.tool_quat = pos, mat_quat(data.xmat[b].tolist())
        s.tool_portal = tuple(data.qpos[self.tool.qadr].tolist())
        previous = s.tool_potential
        self.errors(s, model, data)
        s.prev_tool_potential = s.tool_potential if first else previous

    def errors(self, s: TaskState, model, data) -> None:
        """Target-dependent tool quantities: tip-to-target vector, touching, contacts elsewhere, in view, potential."""
        p, t = s.tool_pos, s.target_pos
        d = (t[0] - p[0], t[1] - p[1], t[2] - p[2])
        s.tool_to_target, s.tool_distance = d, norm(d)
        s.tool_touching = s.tool_distance <= self.touch
        scope = bad = 0
        if data.ncon:  # (slicing the contacts costs more than the rest of the step: only when there are some)
            for (g1, g2), (x, y, z) in zip(data.contact.geom.tolist(), data.contact.pos.tolist()):
                if g1 not in self.tips and g2 not in self.tips:
                    scope += 1 if self.scope_tip in (g1, g2) else 0  # loose bodies resting: no event
                    continue
                on_target = norm((x - t[0], y - t[1], z - t[2])) <= self.target_radius
                bad += 0 if self.tool.tip_geom in (g1, g2) and on_target else 1
        s.tool_contacts, s.contacts = bad, scope + bad
        e = (p[0] - s.cam_pos[0], p[1] - s.cam_pos[1], p[2] - s.cam_pos[2])
        s.tool_in_view = dot(e, s.cam_fwd) > math.cos(self.half_fov) * max(norm(e), 1e-9)
        s.tool_ok = s.tool_touching and bad == 0
        s.tool_potential = -s.tool_distance / TOOL_SCALE


def place_tools(task: CompiledTask, data: mujoco.MjData, q: np.ndarray) -> np.ndarray:
    """Set every instrument's coordinates (clipped to their ranges) and servo targets; return the clipped q."""
    out, i = [], 0
    for t in task.instruments:
        k = len(t.qadr)
        qi = np.minimum(np.maximum(q[i : i + k], t.ranges[:, 0]), t.ranges[:, 1])
        data.qpos[t.qadr] = qi
        data.ctrl[t.ctrl] = qi
        out.append(qi)
        i += k
    return np.concatenate(out)


def tool_start(task: CompiledTask, rng: np.random.Generator) -> np.ndarray:
    """Every instrument's start coordinates plus their uniform noise."""
    out = []
    for t in task.instruments:
        st = t.spec.start
        q = np.array([math.radians(st.pitch_deg), math.radians(st.yaw_deg), st.insertion, math.radians(st.roll_deg)])
        noise = np.array(st.noise) * np.array([math.pi / 180, math.pi / 180, 1.0, math.pi / 180])
        out.append(q + rng.uniform(-1.0, 1.0, 4) * noise)
        if t.spec.kind == "grasper":
            out.append([math.radians(st.jaw_deg)])
    return np.concatenate(out)
