"""Observation terms: pure functions of the task state returning fixed-size tuples of floats."""

from __future__ import annotations

import math

from .registry import OBSERVATION_TERMS
from .state import TaskState
from .vec import cross, dot, norm, sub

term = OBSERVATION_TERMS.register


@term(size=3)
def tip_pos(s: TaskState) -> tuple:
    """Scope tip position in the world (m)."""
    return s.tip_pos


@term(size=3)
def camera_position(s: TaskState) -> tuple:
    """Endoscope camera position in the world (m): the liver tour's whole state."""
    return s.cam_pos


@term(size=4)
def tip_quat(s: TaskState) -> tuple:
    """Camera orientation quaternion (w, x, y, z)."""
    return s.tip_quat


@term(size=3)
def tip_vel(s: TaskState) -> tuple:
    """Tip linear velocity (m/s)."""
    return s.tip_vel


@term(size=4)
def tip_quat_rate(s: TaskState) -> tuple:
    """Time derivative of the camera quaternion (1/s)."""
    return s.tip_quat_rate


@term(size=3)
def target_pos(s: TaskState) -> tuple:
    """Position of the current avatar (m)."""
    return s.target_pos


@term(size=4)
def target_quat(s: TaskState) -> tuple:
    """Orientation quaternion of the current avatar (w, x, y, z)."""
    return s.target_quat


@term(size=3)
def alignment(s: TaskState) -> tuple:
    """Cross product of the camera's forward vector with the avatar's forward vector."""
    return cross(s.cam_fwd, s.target_fwd)


@term(size=3)
def target_in_camera(s: TaskState) -> tuple:
    """Unit direction to the avatar in camera coordinates (x right, y up, z forward)."""
    d = sub(s.target_pos, s.cam_pos)
    n = norm(d) or 1.0
    return (dot(d, s.cam_right) / n, dot(d, s.cam_up) / n, dot(d, s.cam_fwd) / n)


@term(size=2)
def horizon_error(s: TaskState) -> tuple:
    """Sine and cosine of the angle between the avatar's up and the image's up."""
    x, y = dot(s.target_up, s.cam_right), dot(s.target_up, s.cam_up)
    n = math.hypot(x, y) or 1.0
    return (x / n, y / n)


@term(size=1)
def distance_error(s: TaskState) -> tuple:
    """Signed distance outside the cue's range, in units of the range's width."""
    return (s.distance_error / (s.dist_hi - s.dist_lo),)


@term(size=1)
def dwell(s: TaskState) -> tuple:
    """Fill of the dwell bar (0 to 1)."""
    return (s.dwell,)


@term(size=1)
def subtask_fraction(s: TaskState) -> tuple:
    """Share of the subtasks already completed."""
    return (s.subtask / s.subtasks_total,)


@term(size=1)
def elapsed(s: TaskState) -> tuple:
    """Share of the episode's time limit gone (0 to 1): with a time limit, the state says how much time is left."""
    return (s.time / s.time_limit,)


@term(size=5)
def portal(s: TaskState) -> tuple:
    """Portal coordinates scaled to [-1, 1] over their ranges."""
    return tuple(2.0 * (q - lo) / (hi - lo) - 1.0 for q, lo, hi in zip(s.portal, s.portal_lo, s.portal_hi))


@term(size=5)
def portal_vel(s: TaskState) -> tuple:
    """Rates of the portal coordinates (rad/s, m/s)."""
    return s.portal_vel


@term(size=1)
def contact(s: TaskState) -> tuple:
    """1 while the tip touches the shell or the plate, else 0: the contact feature as part of the state."""
    return (1.0 if s.contacts else 0.0,)


@term(size=3)
def next_target(s: TaskState) -> tuple:
    """Position of the avatar after the current one (the current one if it is the last)."""
    return s.goals
