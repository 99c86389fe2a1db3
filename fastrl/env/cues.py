"""The cue state machine: tolerances -> green -> dwell -> subtask complete -> next avatar."""

from __future__ import annotations

from ..terms.state import TaskState


def cue_checks(s: TaskState) -> tuple[bool, bool, bool]:
    """Which tolerances hold: centring, horizon, distance."""
    return s.centring <= s.tol_centring, s.horizon <= s.tol_horizon, s.dist_lo <= s.distance <= s.dist_hi


def cue_green(s: TaskState) -> bool:
    """Every tolerance holds, and the family's own condition (an instrument touching the target and nothing else)."""
    c, h, d = cue_checks(s)
    return c and h and d and s.task_ok


def update_dwell(s: TaskState, elapsed: float, dt: float) -> float:
    """Set green, dwell fill and completion on the state; return the new dwell time elapsed."""
    c, h, d = cue_checks(s)
    s.green = c and h and d and s.task_ok
    elapsed = elapsed + dt if s.green else 0.0
    s.prev_dwell = s.dwell
    s.dwell = 1.0 if s.dwell_time <= 0 else min(1.0, elapsed / s.dwell_time)
    s.dwell_gain = max(0.0, s.dwell - s.dwell_best)
    s.dwell_best = max(s.dwell_best, s.dwell)
    s.completed = s.green and elapsed >= s.dwell_time - 1e-9
    return elapsed
