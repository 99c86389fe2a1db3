"""Read the instruments into the task state: every tip's pose, velocity and target vector, contacts."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..model.compiler import CompiledTask
from ..terms.state import InstrumentState
from ..terms.vec import dot, mat_quat, norm

INSTRUMENT_SCALE = 0.02  # metres of tip-to-target distance per unit of the instrument potential


class InstrumentSensor:
    """Fills an InstrumentState's instrument fields from MjData: every tip; the first is the working one."""

    def __init__(self, task: CompiledTask):
        self.task = task
        self.working = task.instruments[0]
        self.tips = {t.tip_geom for t in task.instruments}
        self.scope_tip = task.tip_geom
        self.touch = self.working.spec.touch
        self.touches = [t.spec.touch for t in task.instruments]
        self.target_radius = task.targets.size
        self.half_fov = math.radians(0.5 * task.spec.scope.fov_deg)
        self.qadr = np.concatenate([t.qadr for t in task.instruments])
        lo = np.concatenate([t.ranges[:, 0] for t in task.instruments])
        hi = np.concatenate([t.ranges[:, 1] for t in task.instruments])
        self.scale, self.offset = 2.0 / (hi - lo), -2.0 * lo / (hi - lo) - 1.0

    def read(self, s: InstrumentState, model: mujoco.MjModel, data: mujoco.MjData, first: bool) -> None:
        """Update every tip's pose and velocity, the instruments' coordinates, contacts and target errors."""
        pos = [tuple(data.xpos[t.tip_body].tolist()) for t in self.task.instruments]
        if first:
            vel = [(0.0, 0.0, 0.0)] * len(pos)
        else:
            k, before = 1.0 / s.dt, s.instruments_pos
            vel = [
                ((p[0] - before[3 * i]) * k, (p[1] - before[3 * i + 1]) * k, (p[2] - before[3 * i + 2]) * k)
                for i, p in enumerate(pos)
            ]
        quats = [mat_quat(data.xmat[t.tip_body].tolist()) for t in self.task.instruments]
        s.instrument_vel, s.instrument_pos, s.instrument_quat = vel[0], pos[0], quats[0]
        s.instruments_pos, s.instruments_vel, s.instruments_quat = _flat(pos), _flat(vel), _flat(quats)
        q = data.qpos[self.qadr]
        s.instrument_portal = tuple(q[: len(self.working.qadr)].tolist())
        s.instruments_portal = tuple(np.clip(q * self.scale + self.offset, -1.0, 1.0).tolist())  # (limits are soft)
        previous = s.instrument_potential
        self.errors(s, model, data)
        s.prev_instrument_potential = s.instrument_potential if first else previous

    def errors(self, s: InstrumentState, model, data) -> None:
        """Target-dependent quantities: tip-to-target vector, touching, contacts elsewhere, in view, potential."""
        p, t = s.instrument_pos, s.target_pos
        d = (t[0] - p[0], t[1] - p[1], t[2] - p[2])
        s.instrument_to_target, s.instrument_distance = d, norm(d)
        s.instrument_touching = s.instrument_distance <= self.touch
        scope = bad = 0
        if data.ncon:  # (slicing the contacts costs more than the rest of the step: only when there are some)
            for (g1, g2), (x, y, z) in zip(data.contact.geom.tolist(), data.contact.pos.tolist()):
                if g1 not in self.tips and g2 not in self.tips:
                    scope += 1 if self.scope_tip in (g1, g2) else 0  # loose bodies resting: no event
                    continue
                on_target = norm((x - t[0], y - t[1], z - t[2])) <= self.target_radius
                bad += 0 if self.working.tip_geom in (g1, g2) and on_target else 1
        s.instrument_contacts, s.contacts = bad, scope + bad
        s.instrument_in_view = self.in_view(s, p)
        s.task_ok = s.instrument_touching and bad == 0
        s.instrument_potential = -s.instrument_distance / INSTRUMENT_SCALE
        if len(self.touches) == 1:
            s.instruments_to_target = d
            s.instruments_touching, s.instruments_in_view = (s.instrument_touching,), (s.instrument_in_view,)
            return
        tips = [s.instruments_pos[i : i + 3] for i in range(0, len(s.instruments_pos), 3)]
        vectors = [(t[0] - x[0], t[1] - x[1], t[2] - x[2]) for x in tips]
        s.instruments_to_target = _flat(vectors)
        s.instruments_touching = tuple(norm(v) <= r for v, r in zip(vectors, self.touches))
        s.instruments_in_view = tuple(self.in_view(s, x) for x in tips)

    def in_view(self, s: InstrumentState, p: tuple) -> bool:
        """Tip position p lies inside the scope's field of view."""
        e = (p[0] - s.cam_pos[0], p[1] - s.cam_pos[1], p[2] - s.cam_pos[2])
        return dot(e, s.cam_fwd) > math.cos(self.half_fov) * max(norm(e), 1e-9)


def _flat(rows: list[tuple]) -> tuple:
    """Concatenate tuples."""
    return tuple(v for row in rows for v in row)


def place_instrument_joints(task: CompiledTask, data: mujoco.MjData, q: np.ndarray) -> np.ndarray:
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


def instrument_start(task: CompiledTask) -> list[np.ndarray]:
    """Every instrument's start pitch, yaw, insertion and roll (rad, m), as the spec gives them."""
    out = []
    for t in task.instruments:
        st = t.spec.start
        out.append(
            np.array([math.radians(st.pitch_deg), math.radians(st.yaw_deg), st.insertion, math.radians(st.roll_deg)])
        )
    return out


def with_jaws(task: CompiledTask, portal: list[np.ndarray]) -> np.ndarray:
    """Every instrument's coordinates: its portal coordinates, then a grasper's start jaw."""
    out = []
    for t, q in zip(task.instruments, portal):
        out.append(q)
        if t.spec.kind == "grasper":
            out.append([math.radians(t.spec.start.jaw_deg)])
    return np.concatenate(out)
