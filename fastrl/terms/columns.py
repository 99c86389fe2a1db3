"""Array forms of the scope's observation terms and reward features, for replay: each the same arithmetic as its
scalar term, in the same order, over every sample of a trajectory at once. A state's columns hold (T,) arrays for
its scalars and (T, k) arrays for its tuples; the fixed ones (time limit, ranges, gamma) stay scalars or tuples.

`tests/env/test_column_replay.py` checks each form against its scalar term on the states of real replays."""

from __future__ import annotations

import math
from collections.abc import Callable
from types import SimpleNamespace

import numpy as np

from .rewards import _GAUSS

Columns = SimpleNamespace  # a TaskState's fields as arrays over samples

OBSERVATION_COLUMNS: dict[str, Callable[[Columns], np.ndarray]] = {}
FEATURE_COLUMNS: dict[str, Callable[..., np.ndarray]] = {}


def _observation(fn):
    """Register fn as the array form of the observation term of the same name."""
    OBSERVATION_COLUMNS[fn.__name__] = fn
    return fn


def _feature(fn):
    """Register fn as the array form of the reward feature of the same name."""
    FEATURE_COLUMNS[fn.__name__] = fn
    return fn


def _libm(fn: Callable) -> Callable[..., np.ndarray]:
    """A `math` function over arrays, element by element: numpy's own acos, atan2, hypot and exp differ from the C
    library's, which the scalar terms use, in the last bit of about one value in ten."""

    def over(*arrays) -> np.ndarray:
        """fn of each element of equally long 1-d arrays."""
        columns = [np.asarray(a, float).tolist() for a in arrays]
        return np.fromiter(map(fn, *columns), float, len(columns[0]))

    return over


acos, atan2, hypot, exp = _libm(math.acos), _libm(math.atan2), _libm(math.hypot), _libm(math.exp)


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise a . b of (T, 3) arrays, summed in vec.dot's order."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def norm(a: np.ndarray) -> np.ndarray:
    """Row-wise |a| of a (T, 3) array."""
    return np.sqrt(a[:, 0] * a[:, 0] + a[:, 1] * a[:, 1] + a[:, 2] * a[:, 2])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise a x b of (T, 3) arrays."""
    return np.stack(
        [
            a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
        ],
        axis=1,
    )


def mat_quat(m: np.ndarray) -> np.ndarray:
    """Row-major rotations (T, 9) to unit quaternions (T, 4) with w >= 0, branch by branch as vec.mat_quat."""
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = m.T
    q = np.empty((len(m), 4))
    t = m00 + m11 + m22
    a = t > 0
    b = ~a & (m00 > m11) & (m00 > m22)
    c = ~a & ~b & (m11 > m22)
    d = ~a & ~b & ~c
    r = np.sqrt(t[a] + 1.0) * 2
    q[a] = np.stack([0.25 * r, (m21[a] - m12[a]) / r, (m02[a] - m20[a]) / r, (m10[a] - m01[a]) / r], axis=1)
    r = np.sqrt(1.0 + m00[b] - m11[b] - m22[b]) * 2
    q[b] = np.stack([(m21[b] - m12[b]) / r, 0.25 * r, (m01[b] + m10[b]) / r, (m02[b] + m20[b]) / r], axis=1)
    r = np.sqrt(1.0 + m11[c] - m00[c] - m22[c]) * 2
    q[c] = np.stack([(m02[c] - m20[c]) / r, (m01[c] + m10[c]) / r, 0.25 * r, (m12[c] + m21[c]) / r], axis=1)
    r = np.sqrt(1.0 + m22[d] - m00[d] - m11[d]) * 2
    q[d] = np.stack([(m10[d] - m01[d]) / r, (m02[d] + m20[d]) / r, (m12[d] + m21[d]) / r, 0.25 * r], axis=1)
    q[q[:, 0] < 0] *= -1.0
    return q


def outside_band(s: Columns) -> np.ndarray:
    """TaskState.distance_error over samples."""
    below, above = s.distance < s.dist_lo, s.distance > s.dist_hi
    return np.where(below, s.distance - s.dist_lo, np.where(above, s.distance - s.dist_hi, 0.0))


def cue_potential(s: Columns) -> np.ndarray:
    """rewards.cue_potential over samples."""
    span = s.dist_hi - s.dist_lo
    return -(s.centring / s.tol_centring + s.horizon / s.tol_horizon + np.abs(outside_band(s)) / span)


def tolerance(x: np.ndarray, lo, hi, margin: float) -> np.ndarray:
    """rewards.tolerance over samples."""
    d = np.where(x < lo, lo - x, x - hi) * _GAUSS
    far = d >= 1e6 * margin  # the scalar form returns 0 there without computing the kernel
    outside = exp(-0.5 * (np.where(far, 0.0, d) / margin) ** 2)
    outside[far] = 0.0
    return np.where((lo <= x) & (x <= hi), 1.0, outside)


# ---- observation terms --------------------------------------------------------------------------
def _field(name: str) -> Callable[[Columns], np.ndarray]:
    """The array form of a term that returns one of the state's fields."""
    return lambda s: getattr(s, name)


OBSERVATION_COLUMNS |= {
    **{n: _field(n) for n in ("tip_pos", "tip_quat", "tip_vel", "tip_quat_rate", "target_pos", "target_quat")},
    **{"portal_vel": _field("portal_vel"), "camera_position": _field("cam_pos"), "next_target": _field("goals")},
}


@_observation
def alignment(s: Columns) -> np.ndarray:
    """observations.alignment."""
    return cross(s.cam_fwd, s.target_fwd)


@_observation
def target_in_camera(s: Columns) -> np.ndarray:
    """observations.target_in_camera."""
    d = s.target_pos - s.cam_pos
    n = norm(d)
    n = np.where(n == 0, 1.0, n)
    return np.stack([dot(d, s.cam_right) / n, dot(d, s.cam_up) / n, dot(d, s.cam_fwd) / n], axis=1)


@_observation
def horizon_error(s: Columns) -> np.ndarray:
    """observations.horizon_error."""
    x, y = dot(s.target_up, s.cam_right), dot(s.target_up, s.cam_up)
    n = hypot(x, y)
    n = np.where(n == 0, 1.0, n)
    return np.stack([x / n, y / n], axis=1)


@_observation
def distance_error(s: Columns) -> np.ndarray:
    """observations.distance_error."""
    return (outside_band(s) / (s.dist_hi - s.dist_lo))[:, None]


@_observation
def dwell(s: Columns) -> np.ndarray:
    """observations.dwell."""
    return s.dwell[:, None]


@_observation
def subtask_fraction(s: Columns) -> np.ndarray:
    """observations.subtask_fraction."""
    return (s.subtask / s.subtasks_total)[:, None]


@_observation
def elapsed(s: Columns) -> np.ndarray:
    """observations.elapsed."""
    return (s.time / s.time_limit)[:, None]


@_observation
def portal(s: Columns) -> np.ndarray:
    """observations.portal."""
    lo, hi = np.array(s.portal_lo), np.array(s.portal_hi)
    return 2.0 * (s.portal - lo) / (hi - lo) - 1.0


@_observation
def contact(s: Columns) -> np.ndarray:
    """observations.contact."""
    return (s.contacts > 0).astype(float)[:, None]


# ---- reward features -----------------------------------------------------------------------------
FEATURE_COLUMNS |= {
    "progress": _field("dwell_gain"),
    "rays": _field("ray_fraction"),
    "completed": lambda s: s.completed.astype(float),
    "contact": lambda s: (s.contacts > 0).astype(float),
    "time": lambda s: np.ones(len(s.time)),
}


@_feature
def velocity(s: Columns, max_speed: float = 0.05) -> np.ndarray:
    """rewards.velocity."""
    return np.maximum(0.0, s.tip_speed - max_speed) / max_speed


@_feature
def distance(s: Columns, margin: float = 0.02) -> np.ndarray:
    """rewards.distance."""
    return tolerance(s.distance, s.dist_lo, s.dist_hi, margin)


@_feature
def angle(s: Columns, margin_deg: float = 20.0) -> np.ndarray:
    """rewards.angle."""
    return tolerance(s.centring, 0.0, s.tol_centring, math.radians(margin_deg))


@_feature
def horizon(s: Columns, margin_deg: float = 30.0) -> np.ndarray:
    """rewards.horizon."""
    return tolerance(s.horizon, 0.0, s.tol_horizon, math.radians(margin_deg))


@_feature
def visible(s: Columns) -> np.ndarray:
    """rewards.visible."""
    return (s.centring < 0.5 * s.fov).astype(float)


@_feature
def line_deviation(s: Columns, scale: float = 0.01) -> np.ndarray:
    """rewards.line_deviation."""
    return s.line_deviation / scale


@_feature
def steadiness(s: Columns, scale: float = 1.0) -> np.ndarray:
    """rewards.steadiness."""
    return norm(s.tip_accel) / scale


@_feature
def shaft_motion(s: Columns) -> np.ndarray:
    """rewards.shaft_motion."""
    return hypot(s.portal_vel[:, 0], s.portal_vel[:, 1])


@_feature
def shaping(s: Columns) -> np.ndarray:
    """rewards.shaping."""
    return s.gamma * s.potential - s.prev_potential
