"""Families of trainee deficits, named for what raters grade: most a direction in SkillProfile space at novice
severity (how the trainee acts), five a kinematic overlay on what was recorded (fastrl.data.overlays); a subject
mixes the families of its cohort, the level setting the total severity."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .skill import NOVICE, SkillProfile, skill_gap

MOST_MIXED = 3  # a subject of a mixed cohort shows at most this many families


@dataclass(frozen=True)
class Family:
    """One kind of deficit: its profile at novice severity (or the overlay it lays on the recording) and the rating
    items and kinematic signs it stands for."""

    novice: SkillProfile
    grades: str
    overlay: str | None = None  # a kinematic overlay of fastrl.data.overlays instead of a way of acting


FAMILIES = {
    "classic": Family(NOVICE, "the project's first trainee model: motor noise, tremor, delay, overshoot, search"),
    "flow": Family(
        SkillProfile(idle=1.5, hesitation=0.03),
        "ASSET flow of procedure, GOALS autonomy: idle time before each step and pauses in it",
    ),
    "speed": Family(SkillProfile(slowness=0.65), "OSATS time and motion: slow, deliberate movement throughout"),
    "depth": Family(SkillProfile(depth=20.0), "GOALS depth perception: the viewing distance misjudged, then corrected"),
    "field_of_view": Family(
        SkillProfile(aim=4.0), "ASSET field of view: the target held off the image centre until noticed"
    ),
    "horizon": Family(
        SkillProfile(horizon=9.0, optics=0.6),
        "ASSET camera dexterity: a tilted horizon, views solved with the shaft instead of the light cable",
    ),
    "economy": Family(SkillProfile(detour=0.8), "GOALS efficiency: detours by a wrong place, longer paths"),
    "corrections": Family(
        SkillProfile(dither=0.25, overshoot=2.0),
        "OSATS instrument handling: back-and-forth corrections and overshoot, jerky motion",
    ),
    "safety": Family(
        SkillProfile(bump=0.03), "OSATS respect for tissue, ASSET safety: the scope pushed in until it touches"
    ),
    "slowed": Family(SkillProfile(), "OSATS time and motion: the same path at a slower, wandering speed", "slowed"),
    "jitter": Family(SkillProfile(), "steadiness (tremor): 3-8 Hz shake on the recorded motion", "jitter"),
    "drift": Family(SkillProfile(), "ASSET field of view: the view drifts slowly off, corrected late", "drift"),
    "paused": Family(
        SkillProfile(), "ASSET flow of procedure: stops mid-motion on the recording, then goes on", "paused"
    ),
    "retraced": Family(
        SkillProfile(), "GOALS efficiency: stretches of path undone and done again (lost, then found)", "retraced"
    ),
}


WITH_INSTRUMENTS = ("classic", "flow", "speed", "corrections")  # what instruments_trainee.py acts out


def family_names(text: str) -> tuple[str, ...]:
    """Families named in a comma-separated list ('all': every one); ValueError names an unknown one."""
    names = tuple(FAMILIES) if text.strip() == "all" else tuple(n.strip() for n in text.split(",") if n.strip())
    unknown = [n for n in names if n not in FAMILIES]
    if unknown or not names:
        raise ValueError(
            f"unknown trainee family {unknown[0] if unknown else text!r}: choose from {', '.join(FAMILIES)}"
        )
    return names


def foreign_family(families: tuple[str, ...], instruments: bool) -> str | None:
    """Why a task cannot show these families (None: it can): scope-only deviations on a task with instruments."""
    foreign = [f for f in families if instruments and f not in WITH_INSTRUMENTS]
    if foreign:
        return f"family {foreign[0]} deviates the scope alone; two-handed tasks take {', '.join(WITH_INSTRUMENTS)}"
    return None


def draw_mix(families: tuple[str, ...], seed: int) -> dict[str, float]:
    """A subject's share of each family (summing to 1): one family alone, or up to MOST_MIXED with random weights."""
    if len(families) == 1:
        return {families[0]: 1.0}
    rng = np.random.default_rng([seed, 4391])  # a stream of its own: the trainee's draws stay as they were
    n = int(rng.integers(1, min(MOST_MIXED, len(families)) + 1))
    chosen = rng.choice(len(families), n, replace=False)
    weights = rng.dirichlet(np.ones(n))
    return {families[int(i)]: float(w) for i, w in zip(chosen, weights)}


def mixed_profile(mix: dict[str, float], level: int, levels: int) -> SkillProfile:
    """The profile of a subject at a level: each family's novice profile scaled by its share of the level's gap."""
    gap, profile = skill_gap(level, levels), SkillProfile()
    for name, share in mix.items():
        profile = profile.plus(FAMILIES[name].novice.scaled(gap * share))
    return profile


def overlay_severities(mix: dict[str, float], level: int, levels: int) -> dict[str, float]:
    """The severity of each kinematic overlay in a subject's mix at a level (its share of the level's gap)."""
    gap = skill_gap(level, levels)
    return {FAMILIES[n].overlay: gap * share for n, share in mix.items() if FAMILIES[n].overlay and gap * share > 0}
