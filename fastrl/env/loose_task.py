"""The grasping tasks (LooseBodies): a grasper takes each loose body (a weld switched on) and drops it in the cup."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..model.compiler import CompiledTask
from ..terms import EpisodeStart
from ..terms.state import TaskState
from .instrument_task import InstrumentTask

CLOSED, OPEN = math.radians(8.0), math.radians(20.0)  # jaw below: closed; above: open
GRAB = 0.007  # the tip closes on a body within this distance of its centre (m)
CUP_LIFT = 0.001  # the cup's target point above its floor (m)


class LooseBodies:
    """Holds which body is grasped, points the cue at the current body (or the cup once it is held) and checks drops."""

    def __init__(self, task: CompiledTask):
        m, spec = task.model, task.spec
        self.task = task
        self.bodies = [m.body(f"loose_{i}").id for i in range(len(spec.task.bodies))]
        self.joints = [int(m.jnt_qposadr[m.joint(f"loose_{i}").id]) for i in range(len(self.bodies))]
        self.dofs = [int(m.jnt_dofadr[m.joint(f"loose_{i}").id]) for i in range(len(self.bodies))]
        self.welds = [m.equality(f"hold_{i}").id for i in range(len(self.bodies))]
        self.home = [np.array([*b.at, b.radius + 1e-4, 1.0, 0.0, 0.0, 0.0]) for b in spec.task.bodies]
        self.grasper = next(t for t in task.instruments if t.spec.kind == "grasper")
        cup = spec.task.cup
        self.cup = np.array([*cup.at, CUP_LIFT])
        self.cup_radius, self.cup_height = cup.radius, cup.height
        self.held, self.jaw, self.on_cup, self.switched = -1, 0.0, False, False

    def reset(self, data: mujoco.MjData) -> None:
        """Bodies back on their spots, nothing held."""
        for adr, home in zip(self.joints, self.home):
            data.qpos[adr : adr + 7] = home
        for w in self.welds:
            data.eq_active[w] = 0
        self.held, self.jaw = -1, float(data.qpos[self.grasper.qadr[4]])
        self.on_cup = self.switched = False

    def poses(self, data: mujoco.MjData) -> np.ndarray:
        """Every body's position and quaternion (wxyz), (k, 7)."""
        return np.array([data.qpos[adr : adr + 7] for adr in self.joints])

    def place(self, data: mujoco.MjData, poses: np.ndarray) -> None:
        """Put the bodies at recorded poses (k, 7), at rest (replay: their physics is not in the portal coordinates)."""
        poses = np.asarray(poses, float)
        if poses.shape != (len(self.joints), 7) or not np.isfinite(poses).all():
            raise ValueError(f"bodies must be {len(self.joints)} finite poses of 7 numbers, got shape {poses.shape}")
        for adr, dof, pose in zip(self.joints, self.dofs, poses):
            q = pose[3:] / (np.linalg.norm(pose[3:]) or 1.0)
            data.qpos[adr : adr + 7] = np.concatenate([pose[:3], q])
            data.qvel[dof : dof + 6] = 0.0

    def update(self, task: LooseBodiesTask, k: int) -> None:
        """Grasp or release body k by the jaw, and move subtask k's target to the body or, once held, the cup."""
        m, d = task.model, task.data
        jaw = float(d.qpos[self.grasper.qadr[4]])
        tip = d.xpos[self.grasper.tip_body]
        body = d.xpos[self.bodies[k]]
        if self.held < 0 and jaw <= CLOSED < self.jaw and np.linalg.norm(body - tip) <= GRAB:
            self._hold(m, d, k)
        elif self.held >= 0 and jaw >= OPEN:
            d.eq_active[self.welds[self.held]] = 0
            self.held = -1
        self.jaw = jaw
        on_cup = self.held == k or self.over_cup(d, k)
        self.switched, self.on_cup = on_cup != self.on_cup, on_cup
        goal = self.cup if on_cup else body
        t = task.state
        task.t_pos[k] = goal
        if t.subtask == k:
            t.target_pos = tuple(goal.tolist())
        t.prev_instrument_holding, t.instrument_holding = t.instrument_holding, self.held == k

    def settle(self, s: TaskState) -> None:
        """After the target moved between the body and the cup: no shaping for the jump itself."""
        if self.switched:
            s.prev_potential, s.prev_instrument_potential = s.potential, s.instrument_potential

    def over_cup(self, data: mujoco.MjData, k: int) -> bool:
        """Body k is above the cup's floor (in it, or falling into it)."""
        p = data.xpos[self.bodies[k]]
        return math.hypot(p[0] - self.cup[0], p[1] - self.cup[1]) < self.cup_radius

    def in_cup(self, data: mujoco.MjData, k: int) -> bool:
        """Body k lies inside the cup."""
        return self.over_cup(data, k) and data.xpos[self.bodies[k]][2] < self.cup_height

    def done(self, s: TaskState, data: mujoco.MjData, k: int) -> bool:
        """Body k rests in the cup, released."""
        return self.held != k and self.in_cup(data, k)

    def _hold(self, m: mujoco.MjModel, d: mujoco.MjData, k: int) -> None:
        """Weld body k to the grasper's tip where it is now."""
        s = self.grasper.tip_body
        rs, rb = d.xmat[s].reshape(3, 3), d.xmat[self.bodies[k]].reshape(3, 3)
        w = self.welds[k]
        m.eq_data[w, 0:3] = 0.0
        m.eq_data[w, 3:6] = rs.T @ (d.xpos[self.bodies[k]] - d.xpos[s])
        q = np.zeros(4)
        mujoco.mju_mat2Quat(q, (rs.T @ rb).ravel())
        m.eq_data[w, 6:10] = q
        d.eq_active[w] = 1
        self.held = k


class LooseBodiesTask(InstrumentTask):
    """The instrument task with a grasper and loose bodies: each body's target is the body, then the cup."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.loose = LooseBodies(self.compiled)

    def place_start(self, start: EpisodeStart, options: dict) -> None:
        """Bodies back on their spots (or where options put them), nothing held; the scope and the instruments."""
        self.loose.reset(self.data)
        super().place_start(start, options)
        if options.get("bodies") is not None:
            self.loose.place(self.data, options["bodies"])
            mujoco.mj_forward(self.model, self.data)

    def sense(self, first: bool) -> None:
        """Grasp or release, read the scope and the instruments; green waits on the body resting in the cup."""
        k = min(self.done_count, len(self.t_pos) - 1)
        self.loose.update(self, k)
        super().sense(first)
        s = self.state
        s.task_ok = self.loose.done(s, self.data, k)
        self.loose.settle(s)

    def place_recorded(self, portal, instruments=None, bodies=None) -> None:
        """Replay: the bodies (if recorded), the scope and the instruments."""
        if bodies is not None:
            self.loose.place(self.data, bodies)
        super().place_recorded(portal, instruments)

    def body_poses(self) -> np.ndarray:
        """Every body's position and quaternion (wxyz), (k, 7)."""
        return self.loose.poses(self.data)
