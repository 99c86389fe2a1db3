"""Reward features and observation terms of the instruments (probe, grasper): pure functions of the task state."""

from __future__ import annotations

from .domain import DISTANCE, LENGTH
from .registry import OBSERVATION_TERMS, REWARD_FEATURES
from .rewards import tolerance
from .state import InstrumentState

feature, term = REWARD_FEATURES.register, OBSERVATION_TERMS.register
INSTRUMENTS = ("instruments",)  # they read the InstrumentState: a spec naming them must declare instruments


@feature(needs=INSTRUMENTS, domains={"within": DISTANCE, "margin": LENGTH})
def tool_near(s: InstrumentState, within: float = 0.004, margin: float = 0.03) -> float:
    """Tolerance kernel of the instrument tip's distance to the target: 1 within `within` m."""
    return tolerance(s.instrument_distance, 0.0, within, margin)


@feature(needs=INSTRUMENTS)
def tool_touch(s: InstrumentState) -> float:
    """1 while the instrument tip touches the target."""
    return 1.0 if s.instrument_touching else 0.0


@feature(needs=INSTRUMENTS)
def tool_in_view(s: InstrumentState) -> float:
    """1 while the instrument tip is inside the scope's field of view."""
    return 1.0 if s.instrument_in_view else 0.0


@feature(needs=INSTRUMENTS)
def tool_contact(s: InstrumentState) -> float:
    """1 while an instrument touches anything but the target (a safety event)."""
    return 1.0 if s.instrument_contacts else 0.0


@feature(needs=INSTRUMENTS)
def tool_shaping(s: InstrumentState) -> float:
    """Potential-based shaping of the tip-to-target distance: gamma * Phi(s') - Phi(s), Phi = -distance / 2 cm."""
    return s.gamma * s.instrument_potential - s.prev_instrument_potential


@feature(needs=INSTRUMENTS)
def grasp_shaping(s: InstrumentState) -> float:
    """+1 when the grasper takes hold of the current body, -1 when it lets go (potential-based: not farmable)."""
    return float(s.instrument_holding) - float(s.prev_instrument_holding)


@term(size=1, needs=INSTRUMENTS)
def tool_holding(s: InstrumentState) -> tuple:
    """1 while the grasper holds the current body, else 0."""
    return (1.0 if s.instrument_holding else 0.0,)


@term(size=3, per="instrument", needs=INSTRUMENTS)
def tool_tip_pos(s: InstrumentState) -> tuple:
    """Every instrument's tip position in the world (m), spec order."""
    return s.instruments_pos


@term(size=4, per="instrument", needs=INSTRUMENTS)
def tool_tip_quat(s: InstrumentState) -> tuple:
    """Every instrument's shaft orientation quaternion (w, x, y, z), spec order."""
    return s.instruments_quat


@term(size=3, per="instrument", needs=INSTRUMENTS)
def tool_tip_vel(s: InstrumentState) -> tuple:
    """Every instrument's tip linear velocity (m/s), spec order."""
    return s.instruments_vel


@term(size=3, per="instrument", needs=INSTRUMENTS)
def tool_to_target(s: InstrumentState) -> tuple:
    """Vector from every instrument's tip to the current target (m), spec order."""
    return s.instruments_to_target


@term(size=1, per="instrument", needs=INSTRUMENTS)
def tool_touching(s: InstrumentState) -> tuple:
    """1 while an instrument's tip touches the target, else 0; one value per instrument."""
    return tuple(1.0 if t else 0.0 for t in s.instruments_touching)


@term(size=1, per="instrument", needs=INSTRUMENTS)
def tool_visible(s: InstrumentState) -> tuple:
    """1 while an instrument's tip is in the scope's field of view, else 0; one value per instrument."""
    return tuple(1.0 if v else 0.0 for v in s.instruments_in_view)


@term(per="coordinate", needs=INSTRUMENTS)
def tool_portal(s: InstrumentState) -> tuple:
    """Every instrument's portal coordinates (and a grasper's jaw) scaled to [-1, 1] over their ranges, clipped."""
    return s.instruments_portal
