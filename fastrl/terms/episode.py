"""Reset and termination terms: what an episode's start randomises and what ends it, registered by name."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .domain import Domain
from .registry import RESET_TERMS, TERMINATION_TERMS
from .state import TaskState

reset = RESET_TERMS.register
termination = TERMINATION_TERMS.register
NOISE_ANGLE = Domain(0.0, 180.0, unit="an angle in degrees")
NOISE_LENGTH = Domain(0.0, 1.0, unit="a length in m")
DEG = math.pi / 180


@dataclass
class EpisodeStart:
    """What an episode starts from, before its Task places it; the reset terms change it in place.

    `at`: each avatar's surface coordinates (plate: m, dome: deg), `on_plate` where each lies; `scope`: the
    portal coordinates (rad, m), `instruments`: each instrument's pitch, yaw, insertion and roll; None where the
    reset's options give them (then nothing is drawn for them).
    """

    at: np.ndarray
    on_plate: np.ndarray
    scope: np.ndarray | None
    instruments: list[np.ndarray] | None


# Applied in the order registered here, whatever the spec's order: the random draws stay in one order.
@reset(domains={"plate": NOISE_LENGTH, "dome": NOISE_ANGLE})
def avatar_jitter(start: EpisodeStart, rng: np.random.Generator, plate: float = 0.0, dome: float = 0.0) -> None:
    """Each avatar moved on its surface by up to `plate` metres on the plate, `dome` degrees on the dome."""
    if plate == 0 and dome == 0:
        return
    for i in range(len(start.at)):
        start.at[i] = start.at[i] + rng.uniform(-1.0, 1.0, 2) * (plate if start.on_plate[i] else dome)


PORTAL_NOISE = {  # the most a start is moved, per portal coordinate (an instrument has no cable: the first four)
    "pitch_deg": NOISE_ANGLE,
    "yaw_deg": NOISE_ANGLE,
    "insertion": NOISE_LENGTH,
    "roll_deg": NOISE_ANGLE,
    "cable_deg": NOISE_ANGLE,
}


def moved(q: np.ndarray, rng: np.random.Generator, amounts: tuple[float, ...]) -> np.ndarray:
    """Portal coordinates moved by uniform noise of up to `amounts` (deg, deg, m, deg[, deg]) each."""
    return q + rng.uniform(-1.0, 1.0, len(amounts)) * (
        np.array(amounts) * np.array([DEG, DEG, 1.0, DEG, DEG][: len(amounts)])
    )


@reset(domains=PORTAL_NOISE)
def scope_noise(
    start: EpisodeStart,
    rng: np.random.Generator,
    pitch_deg: float = 0.0,
    yaw_deg: float = 0.0,
    insertion: float = 0.0,
    roll_deg: float = 0.0,
    cable_deg: float = 0.0,
) -> None:
    """The scope's start moved by uniform noise of up to these amounts per portal coordinate."""
    if start.scope is not None:
        start.scope = moved(start.scope, rng, (pitch_deg, yaw_deg, insertion, roll_deg, cable_deg))


@reset(domains={k: PORTAL_NOISE[k] for k in ("pitch_deg", "yaw_deg", "insertion", "roll_deg")})
def instrument_noise(
    start: EpisodeStart,
    rng: np.random.Generator,
    pitch_deg: float = 0.0,
    yaw_deg: float = 0.0,
    insertion: float = 0.0,
    roll_deg: float = 0.0,
) -> None:
    """Every instrument's start moved by uniform noise of up to these amounts per portal coordinate."""
    if start.instruments is not None:
        start.instruments = [moved(q, rng, (pitch_deg, yaw_deg, insertion, roll_deg)) for q in start.instruments]


@termination
def subtasks_done(s: TaskState) -> bool:
    """Every subtask is completed (the task's success)."""
    return s.subtasks_done >= s.subtasks_total


@termination
def contact(s: TaskState) -> bool:
    """The scope's tip touches the shell or the plate."""
    return s.contacts > 0
