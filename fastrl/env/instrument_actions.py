"""Actions over the scope and its instruments: the scope's own actions, then every instrument coordinate's."""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from ..model.instruments import InstrumentHandles
from ..spec.models import Actions

SCOPE_DISCRETE, SCOPE_BOX = 11, {"continuous": 7, "rates": 5}


def coordinate_steps(cfg: Actions, kind: str, k: int) -> np.ndarray:
    """Per-coordinate increments: discrete steps, or rate x dt maxima (pitch, yaw, insertion, roll, jaw)."""
    if kind == "discrete":
        deg = [cfg.pivot_step_deg, cfg.pivot_step_deg, None, cfg.roll_step_deg, cfg.roll_step_deg]
        lin = cfg.insertion_step
    else:
        deg = [cfg.max_pivot_rate_deg, cfg.max_pivot_rate_deg, None, cfg.max_roll_rate_deg, cfg.max_roll_rate_deg]
        lin = cfg.max_insertion_rate
    return np.array([lin if d is None else math.radians(d) for d in deg][:k])


class InstrumentActions:
    """The scope's actions (first) and every instrument's: discrete +/- steps, or coordinate rates in [-1, 1]."""

    def __init__(self, scope, cfg: Actions, instruments: list[InstrumentHandles], dt: float):
        self.scope, self.instruments, self.mode = scope, instruments, cfg.mode
        self.sizes = [len(t.qadr) for t in instruments]
        self.qadr = np.concatenate([t.qadr for t in instruments])
        self.instrument_lo = np.concatenate([t.ranges[:, 0] for t in instruments])
        self.instrument_hi = np.concatenate([t.ranges[:, 1] for t in instruments])
        steps = np.concatenate([coordinate_steps(cfg, self.mode, k) for k in self.sizes])
        self.instrument_step = steps if self.mode == "discrete" else steps * dt
        self.instrument_lead = 3.0 * self.instrument_step
        n = len(self.qadr)
        if self.mode == "discrete":
            self.space = spaces.Discrete(SCOPE_DISCRETE + 2 * n)
        else:
            self.space = spaces.Box(-1.0, 1.0, (SCOPE_BOX[self.mode] + n,), np.float32)

    def __getattr__(self, name):
        """The scope's action attributes (twist, body, table, step of the scope part) for its expert."""
        return getattr(self.__dict__["scope"], name)

    def reset(self, data, qadr) -> None:
        """Reset the scope's action state."""
        self.scope.reset(data, qadr)

    def copy_from(self, other: InstrumentActions) -> None:
        """Continue with another env's scope action state."""
        self.scope.copy_from(other.scope)

    def targets(self, action, target: list, q: list, model, data) -> list:
        """Servo targets of the scope (first five) and every instrument coordinate."""
        instrument_target = np.array(target[5:])
        pose = data.qpos[self.qadr]
        if self.mode == "discrete":
            try:
                a = int(action)
            except (TypeError, ValueError, OverflowError):
                raise ValueError(
                    f"discrete action must be an integer in [0, {self.space.n - 1}], got {action!r}"
                ) from None
            if not 0 <= a < self.space.n or a != action:
                raise ValueError(f"discrete action must be an integer in [0, {self.space.n - 1}], got {action!r}")
            scope = self.scope.targets(a if a < SCOPE_DISCRETE else 0, target[:5], q, model, data)
            if a >= SCOPE_DISCRETE:
                j, sign = divmod(a - SCOPE_DISCRETE, 2)
                instrument_target[j] += self.instrument_step[j] * (1.0 if sign == 0 else -1.0)
        else:
            a = np.asarray(action, dtype=float).reshape(-1)
            if a.shape != self.space.shape:
                raise ValueError(
                    f"{self.mode} action must have {self.space.shape[0]} values, got shape {np.shape(action)}"
                )
            if not np.all(np.isfinite(a)):
                raise ValueError(f"action has non-finite values: {a.tolist()}")
            k = SCOPE_BOX[self.mode]
            scope = self.scope.targets(a[:k], target[:5], q, model, data)
            instrument_target += np.clip(a[k:], -1.0, 1.0) * self.instrument_step
        instrument_target = np.clip(instrument_target, pose - self.instrument_lead, pose + self.instrument_lead)
        return list(scope) + np.clip(instrument_target, self.instrument_lo, self.instrument_hi).tolist()


def instrument_meanings(instruments: list[InstrumentHandles]) -> list[str]:
    """Names of the discrete actions past the scope's eleven, e.g. 'probe.pitch+'."""
    signs = {"insertion": ("insert", "retract")}
    out = []
    for t in instruments:
        for j in t.joints:
            plus, minus = signs.get(j, (f"{j}+", f"{j}-"))
            out += [f"{t.spec.name}.{plus}", f"{t.spec.name}.{minus}"]
    return out
