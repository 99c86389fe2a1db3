"""Action spaces: 11 discrete portal increments, 7 continuous tip accelerations and cable rate, or 5 portal rates."""

from __future__ import annotations

import math

import mujoco
import numpy as np
from gymnasium import spaces

from ..spec.models import Actions

DISCRETE_MEANINGS = (
    "noop",
    "pitch+",
    "pitch-",
    "yaw+",
    "yaw-",
    "insert",
    "retract",
    "roll+",
    "roll-",
    "cable+",
    "cable-",
)


class DiscreteActions:
    """Discrete(11): no-op, or plus/minus one step on one portal coordinate."""

    def __init__(self, cfg: Actions, ranges: np.ndarray):
        steps = np.array(
            [
                math.radians(cfg.pivot_step_deg),
                math.radians(cfg.pivot_step_deg),
                cfg.insertion_step,
                math.radians(cfg.roll_step_deg),
                math.radians(cfg.cable_step_deg),
            ]
        )
        self.space = spaces.Discrete(11)
        self.table = np.zeros((11, 5))
        for k in range(5):
            self.table[1 + 2 * k, k], self.table[2 + 2 * k, k] = steps[k], -steps[k]
        self.rows = [tuple(r) for r in self.table.tolist()]
        self.lead = (3.0 * steps).tolist()
        self.lo, self.hi = ranges[:, 0].tolist(), ranges[:, 1].tolist()

    def reset(self, data: mujoco.MjData, qadr: np.ndarray) -> None:
        """Nothing to reset."""

    def copy_from(self, other: DiscreteActions) -> None:
        """Nothing to copy: no action state."""

    def targets(self, action, target: list, q: list, model, data) -> list:
        """New servo targets: one increment, kept within the limits and a few steps of the pose."""
        try:
            a = int(action)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(f"discrete action must be an integer in [0, 10], got {action!r}") from None
        if not 0 <= a <= 10 or a != action:
            raise ValueError(f"discrete action must be an integer in [0, 10], got {action!r}")
        out = []
        for t, dq, p, lead, lo, hi in zip(target, self.rows[a], q, self.lead, self.lo, self.hi):
            t = min(max(t + dq, lo, p - lead), hi, p + lead)
            out.append(t)
        return out


class ContinuousActions:
    """Box(7): tip linear acceleration (3), angular acceleration (3), light-cable rate (1), in [-1, 1]."""

    LINEAR_WEIGHT = 10.0  # 1 cm/s of tip motion weighs like 0.1 rad/s in the least-squares map
    LEAD = np.array([0.1, 0.1, 0.01, 0.2, 0.2])  # how far servo targets may run ahead of the pose

    def __init__(self, cfg: Actions, ranges: np.ndarray, dt: float, body: int):
        self.cfg, self.dt, self.body = cfg, dt, body
        self.space = spaces.Box(-1.0, 1.0, (7,), np.float32)
        self.lo, self.hi = ranges[:, 0], ranges[:, 1]
        self.twist = np.zeros(6)
        self.jacp, self.jacr = np.zeros((3, 0)), np.zeros((3, 0))

    def reset(self, data: mujoco.MjData, qadr: np.ndarray) -> None:
        """Start at rest."""
        self.twist[:] = 0.0

    def copy_from(self, other: ContinuousActions) -> None:
        """Continue with another env's commanded twist."""
        self.twist[:] = other.twist

    def targets(self, action, target: list, q: list, model, data) -> list:
        """Integrate the commanded tip twist, map it through the portal Jacobian to servo targets."""
        a = np.asarray(action, dtype=float).reshape(-1)
        if a.shape != (7,):
            raise ValueError(f"continuous action must have 7 values, got shape {np.shape(action)}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action has non-finite values: {a.tolist()}")
        a = np.clip(a, -1.0, 1.0)
        c, dt = self.cfg, self.dt
        tw = self.twist
        tw[:3] += a[:3] * (c.max_accel * dt)
        tw[3:] += a[3:6] * (c.max_ang_accel * dt)
        _cap(tw[:3], c.max_speed)
        _cap(tw[3:], c.max_ang_speed)
        if self.jacp.shape[1] != model.nv:
            self.jacp, self.jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        mujoco.mj_jacBody(model, data, self.jacp, self.jacr, self.body)
        J = np.vstack([self.LINEAR_WEIGHT * self.jacp[:, :4], self.jacr[:, :4]])
        v = np.concatenate([self.LINEAR_WEIGHT * tw[:3], tw[3:]])
        qd = np.linalg.solve(J.T @ J + 1e-6 * np.eye(4), J.T @ v)
        achieved = J @ qd
        tw[:3], tw[3:] = achieved[:3] / self.LINEAR_WEIGHT, achieved[3:]
        t = np.array(target)
        t[:4] += qd * dt
        t[4] += a[6] * c.max_cable_rate * dt
        q = np.array(q)
        t = np.clip(t, q - self.LEAD, q + self.LEAD)
        return np.clip(t, self.lo, self.hi).tolist()


class RateActions:
    """Box(5): portal coordinate rates (pitch, yaw, insertion, roll, cable) in [-1, 1] of their maximum rates."""

    def __init__(self, cfg: Actions, ranges: np.ndarray, dt: float):
        self.space = spaces.Box(-1.0, 1.0, (5,), np.float32)
        self.step = dt * np.array(
            [
                math.radians(cfg.max_pivot_rate_deg),
                math.radians(cfg.max_pivot_rate_deg),
                cfg.max_insertion_rate,
                math.radians(cfg.max_roll_rate_deg),
                cfg.max_cable_rate,
            ]
        )
        self.lead = 3.0 * self.step
        self.lo, self.hi = ranges[:, 0], ranges[:, 1]

    def reset(self, data: mujoco.MjData, qadr: np.ndarray) -> None:
        """Nothing to reset: the servos hold the pose."""

    def copy_from(self, other: RateActions) -> None:
        """Nothing to copy: no action state."""

    def targets(self, action, target: list, q: list, model, data) -> list:
        """Servo targets moved by rate x dt, kept within the limits and a few steps of the pose."""
        a = np.asarray(action, dtype=float).reshape(-1)
        if a.shape != (5,):
            raise ValueError(f"rates action must have 5 values, got shape {np.shape(action)}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action has non-finite values: {a.tolist()}")
        t = np.array(target) + np.clip(a, -1.0, 1.0) * self.step
        q = np.array(q)
        t = np.clip(t, q - self.lead, q + self.lead)
        return np.clip(t, self.lo, self.hi).tolist()


def _cap(v: np.ndarray, limit: float) -> None:
    """Scale v in place so its norm is at most limit."""
    n = math.sqrt(v @ v)
    if n > limit:
        v *= limit / n
