"""Reward features phi(s): pure functions of the task state, registered by name."""

from __future__ import annotations

import math

from .domain import ACCELERATION, ANGLE, LENGTH, SPEED
from .registry import REWARD_FEATURES
from .state import TaskState
from .vec import norm

feature = REWARD_FEATURES.register
_GAUSS = math.sqrt(-2.0 * math.log(0.1))  # kernel value 0.1 at one margin outside the bounds


def tolerance(x: float, lo: float, hi: float, margin: float) -> float:
    """1 inside [lo, hi], Gaussian fall-off to 0.1 at one margin outside (0 far outside, never an overflow)."""
    if lo <= x <= hi:
        return 1.0
    d = (lo - x if x < lo else x - hi) * _GAUSS
    return math.exp(-0.5 * (d / margin) ** 2) if d < 1e6 * margin else 0.0


def cue_potential(s: TaskState) -> float:
    """Minus the sum of the cue errors, each divided by its tolerance."""
    span = s.dist_hi - s.dist_lo
    return -(s.centring / s.tol_centring + s.horizon / s.tol_horizon + abs(s.distance_error) / span)


@feature
def progress(s: TaskState) -> float:
    """Growth of the dwell bar beyond its best so far for this avatar (sums to 1 per avatar: not farmable)."""
    return s.dwell_gain


@feature
def completed(s: TaskState) -> float:
    """1 on the step a subtask is completed."""
    return 1.0 if s.completed else 0.0


@feature
def contact(s: TaskState) -> float:
    """1 while the scope tip touches the shell or the plate (a safety event)."""
    return 1.0 if s.contacts else 0.0


@feature
def time(s: TaskState) -> float:
    """1 every step; give it a negative weight for a time penalty."""
    return 1.0


@feature(domains={"max_speed": SPEED})
def velocity(s: TaskState, max_speed: float = 0.05) -> float:
    """Tip speed above `max_speed` (m/s), relative to it; 0 below."""
    return max(0.0, s.tip_speed - max_speed) / max_speed


@feature(domains={"margin": LENGTH})
def distance(s: TaskState, margin: float = 0.02) -> float:
    """Tolerance kernel of the viewing distance against the cue's range."""
    return tolerance(s.distance, s.dist_lo, s.dist_hi, margin)


@feature(domains={"margin_deg": ANGLE})
def angle(s: TaskState, margin_deg: float = 20.0) -> float:
    """Tolerance kernel of the centring angle against the cue's tolerance."""
    return tolerance(s.centring, 0.0, s.tol_centring, math.radians(margin_deg))


@feature(domains={"margin_deg": ANGLE})
def horizon(s: TaskState, margin_deg: float = 30.0) -> float:
    """Tolerance kernel of the horizon error against the cue's tolerance."""
    return tolerance(s.horizon, 0.0, s.tol_horizon, math.radians(margin_deg))


@feature
def visible(s: TaskState) -> float:
    """1 while the avatar is inside the camera's field of view."""
    return 1.0 if s.centring < 0.5 * s.fov else 0.0


@feature(needs=("rays",))
def rays(s: TaskState) -> float:
    """Share of rays from the camera to points of the avatar that arrive unobstructed and in view."""
    return s.ray_fraction


@feature(domains={"scale": LENGTH})
def line_deviation(s: TaskState, scale: float = 0.01) -> float:
    """Distance from where the optical axis meets the plate to the line, in units of `scale` (m)."""
    return s.line_deviation / scale


@feature(domains={"scale": ACCELERATION})
def steadiness(s: TaskState, scale: float = 1.0) -> float:
    """Tip acceleration magnitude in units of `scale` (m/s^2); weight it negative for steady motion."""
    return norm(s.tip_accel) / scale


@feature
def shaft_motion(s: TaskState) -> float:
    """Pivot speed of the shaft about the portal (rad/s); the periscoping penalty."""
    return math.hypot(s.portal_vel[0], s.portal_vel[1])


@feature
def shaping(s: TaskState) -> float:
    """Potential-based shaping gamma * Phi(s') - Phi(s), Phi = minus the tolerance-scaled cue errors."""
    return s.gamma * s.potential - s.prev_potential
