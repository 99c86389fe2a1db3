"""Actions recovered from recorded states: the simulator is deterministic and can be set to any recorded pose.

At each sample t the scope is where the recording says (pose t, with the servo targets and velocities the
simulation carried so far), each candidate action is stepped, and the action whose next pose is nearest to the
recorded pose t+1 is kept. Discrete: exact search over the 11 actions. Rates and continuous: least squares (damped
Gauss-Newton through the finite-difference Jacobian of the step's next pose in the action), clipped to the action
box. Continuous actions (tip accelerations) are weakly identifiable from one step: the pose lags the servo target.
Distances weigh 1 degree like 1 mm. After each step the pose is set back to the recording (teacher forcing),
so errors do not accumulate; on a recording made in this simulator nothing is changed by that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from .frames import control_grid, nearest_rows
from .poses import resample, resample_bodies, resample_columns
from .trajectory import Trajectory

WEIGHTS = np.array([180 / math.pi, 180 / math.pi, 1000.0, 180 / math.pi, 180 / math.pi])  # 1 deg ~ 1 mm
TOOL_WEIGHTS = np.array([180 / math.pi, 180 / math.pi, 1000.0, 180 / math.pi, 180 / math.pi])  # pitch .. jaw
FD_STEP = 0.05  # finite-difference step in action units
ITERATIONS = 3  # Gauss-Newton iterations for rates / continuous actions
DAMPING = 1e-2  # Levenberg-Marquardt damping: directions the next pose hardly sees stay near the last action
RATE_TOLERANCE = 1e-3  # relative deviation of a sample interval from 1 / control_hz that still counts as on grid


def on_control_grid(traj: Trajectory, hz: float) -> bool:
    """Whether every sample interval is 1 / hz (within RATE_TOLERANCE)."""
    return bool(np.allclose(np.diff(traj.time), 1.0 / hz, rtol=RATE_TOLERANCE, atol=0.0))


def to_control_rate(traj: Trajectory, hz: float) -> Trajectory:
    """The trajectory on the control grid t0 + k / hz, interpolated linearly with roll and cable unwrapped (the
    rule of `fastrl import-poses`), other instruments and free bodies with it, video frames by the nearest frame
    in time (ties: the earlier); its actions are dropped, since they belonged to the old samples."""
    if on_control_grid(traj, hz):
        return traj
    if traj.portal is None:
        time, portal = control_grid(traj.time, hz), None
    else:
        time, portal = resample(traj.time, traj.portal, hz)
    if len(time) < 2:
        raise ValueError(f"shorter than one control step (1/{hz:g} s): cannot be resampled")
    meta = {**traj.meta, "resampled_from": len(traj.time)}
    instruments = resample_columns(time, traj.time, traj.instruments)
    bodies, frames = resample_bodies(time, traj.time, traj.bodies), nearest_rows(time, traj.time, traj.frames)
    return Trajectory(time, portal, meta, instruments=instruments, bodies=bodies, frames=frames)


@dataclass
class Recovered:
    """Recovered actions and how well they explain the recording: per step, the weighted distance (deg ~ mm)
    between the pose they lead to and the recorded next pose."""

    actions: np.ndarray
    residual: np.ndarray


class ActionRecovery:
    """Recovers the actions of recordings in one env (FastEnv), by search or least squares through its physics."""

    def __init__(self, env):
        self.env = env.unwrapped
        self.mode = self.env.task_spec.actions.mode
        self.base = mujoco.MjData(self.env.model)
        tools = self.env.task.instruments
        self.tool_qadr = np.concatenate([t.qadr for t in tools]).astype(int) if tools else np.zeros(0, int)
        self.tool_ranges = np.concatenate([t.ranges for t in tools]) if tools else np.zeros((0, 2))
        self.weights = WEIGHTS

    def _save(self):
        """The physics, servo targets and (continuous mode) commanded twist."""
        u = self.env
        mujoco.mj_copyData(self.base, u.model, u.data)
        twist = u.actions.twist.copy() if hasattr(u.actions, "twist") else None
        return list(u.target), twist

    def _restore(self, saved) -> None:
        """Back to what _save kept."""
        u = self.env
        mujoco.mj_copyData(u.data, u.model, self.base)
        u.target = list(saved[0])
        if saved[1] is not None:
            u.actions.twist[:] = saved[1]

    def _step(self, action) -> np.ndarray:
        """The env's physics step for one action (as FastEnv.step, without scoring); the next portal pose (and the
        instruments' coordinates when the recording has them)."""
        u = self.env
        m, d = u.model, u.data
        u.target = u.actions.targets(action, u.target, tuple(d.qpos[u.task.qadr].tolist()), m, d)
        d.ctrl[:] = u.target
        mujoco.mj_step2(m, d)
        if u.substeps > 1:
            mujoco.mj_step(m, d, nstep=u.substeps - 1)
        d.qpos[u.lens] = -d.qpos[u.cable]
        mujoco.mj_step1(m, d)
        if len(self.weights) > 5:
            return np.concatenate([d.qpos[u.task.qadr], d.qpos[self.tool_qadr]])
        return d.qpos[u.task.qadr].copy()

    def _try(self, saved, action, goal: np.ndarray) -> tuple[np.ndarray, float]:
        """Weighted distance error (vector, and its norm) of one candidate action from the saved state."""
        self._restore(saved)
        diff = (self._step(action) - goal) * self.weights
        return diff, float(np.sqrt(diff @ diff))

    def _discrete(self, saved, goal: np.ndarray) -> tuple[int, float]:
        """The discrete action whose next pose is nearest the goal (the lowest index on ties: no-op first)."""
        dists = [self._try(saved, a, goal)[1] for a in range(self.env.action_space.n)]
        best = int(np.argmin(dists))
        return best, dists[best]

    def _box(self, saved, goal: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, float]:
        """Least squares in the action box: Gauss-Newton from `start`, each step clipped to [-1, 1]."""
        a = np.clip(start, -1.0, 1.0)
        best_a, (r, best) = a, self._try(saved, a, goal)
        for _ in range(ITERATIONS):
            if best < 1e-6:
                break
            J = np.empty((len(goal), len(a)))
            for i in range(len(a)):
                h = FD_STEP if a[i] < 1.0 - FD_STEP else -FD_STEP
                e = a.copy()
                e[i] += h
                J[:, i] = (self._try(saved, e, goal)[0] - r) / h
            step = np.linalg.solve(J.T @ J + DAMPING * np.eye(len(a)), -J.T @ r)
            a = np.clip(a + step, -1.0, 1.0)
            r, dist = self._try(saved, a, goal)
            if dist >= best - 1e-9:
                break
            best_a, best = a, dist
        return best_a.astype(np.float32), best

    def recover(self, traj: Trajectory) -> Recovered:
        """The actions between consecutive samples of a recording (at the control rate) and their residuals."""
        u = self.env
        options = {"portal": traj.portal[0]}
        goals, tools = traj.portal, traj.instruments is not None and len(self.tool_qadr) == traj.instruments.shape[1]
        if tools:  # with instruments: every instrument's coordinates are matched too
            options["instruments"], goals = traj.instruments[0], np.hstack([traj.portal, traj.instruments])
            kinds = [len(t.qadr) for t in u.task.instruments]
            self.weights = np.concatenate([WEIGHTS, *[TOOL_WEIGHTS[:k] for k in kinds]])
        else:
            self.weights = WEIGHTS
        if traj.bodies is not None and u.loose is not None:
            options["bodies"] = traj.bodies[0]
        u.reset(seed=traj.seed, options=options)
        actions, residual = [], []
        previous = np.zeros(u.action_space.shape or (), np.float32)
        for i, goal in enumerate(goals[1:], 1):
            goal = np.asarray(goal, float)
            saved = self._save()
            if self.mode == "discrete":
                action, dist = self._discrete(saved, goal)
            else:
                action, dist = self._box(saved, goal, previous)
                if tools and dist > 1e-6:  # an instrument's servo lead saturates: no gradient back from there
                    again, d0 = self._box(saved, goal, np.zeros_like(previous))
                    action, dist = (again, d0) if d0 < dist else (action, dist)
                previous = action
            self._restore(saved)
            self._step(action)
            u.data.qpos[u.task.qadr] = np.clip(goal[:5], u.task.ranges[:, 0], u.task.ranges[:, 1])  # teacher forcing
            if tools:
                u.data.qpos[self.tool_qadr] = np.clip(goal[5:], self.tool_ranges[:, 0], self.tool_ranges[:, 1])
            if traj.bodies is not None and u.loose is not None:
                u.loose.place(u.data, traj.bodies[i])
            u.data.qpos[u.lens] = -u.data.qpos[u.cable]
            mujoco.mj_step1(u.model, u.data)
            actions.append(action)
            residual.append(dist)
        dtype = np.int64 if self.mode == "discrete" else np.float32
        return Recovered(np.asarray(actions, dtype), np.asarray(residual))


def agreement(true: np.ndarray, recovered: np.ndarray, mode: str) -> dict:
    """How recovered actions compare with true ones: discrete exact-match rate; else mean absolute error."""
    true, recovered = np.asarray(true), np.asarray(recovered)
    n = min(len(true), len(recovered))
    if mode == "discrete":
        return {"steps": n, "exact_match": float(np.mean(true[:n].reshape(-1) == recovered[:n].reshape(-1)))}
    diff = np.abs(np.clip(true[:n], -1.0, 1.0) - recovered[:n])
    return {"steps": n, "mean_abs_error": float(diff.mean()), "max_abs_error": float(diff.max())}
