"""A trainee's skill as parameters of deviation from the scripted expert, graded by level."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

PROBABILITIES = ("motor_noise", "hesitation", "wander", "optics", "slowness", "detour", "dither", "bump")


@dataclass(frozen=True)
class SkillProfile:
    """How a trainee deviates from the scripted expert; every parameter 0 is the expert."""

    motor_noise: float = 0.0  # probability that a step's action is replaced by a random movement
    tremor: float = 0.0  # amplitude (pitch and yaw increments) of a 2 Hz oscillation added to the moves
    delay: float = 0.0  # reaction delay (s): pose and current subtask are seen this late
    overshoot: float = 0.0  # mean extra increments past a coordinate's goal before correcting
    hesitation: float = 0.0  # probability per step of starting an idle pause (about 0.5 s)
    wander: float = 0.0  # probability of a random search sweep instead of a direct move, target out of view
    optics: float = 0.0  # probability per subtask of solving the view by moving the shaft, not the cable
    idle: float = 0.0  # mean planning pause (s) before the first move toward each new avatar
    slowness: float = 0.0  # probability that a step meant to move waits instead (slow, deliberate movement)
    depth: float = 0.0  # sd (increments) of a misjudged insertion depth per avatar, halved whenever noticed
    aim: float = 0.0  # sd (increments) of a misjudged pitch and yaw per avatar (view off-centre), halved when noticed
    horizon: float = 0.0  # sd (increments) of a misjudged roll per avatar (tilted horizon), halved when noticed
    detour: float = 0.0  # probability per avatar of heading first for a wrong place near it
    dither: float = 0.0  # probability that a step meant to move goes the opposite way (back-and-forth corrections)
    bump: float = 0.0  # probability per step of pushing the scope in until it touches something, then backing out

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if not value >= 0.0:  # also rejects NaN
                raise ValueError(f"skill parameter {f.name} must be >= 0, got {value!r}")
        for name in PROBABILITIES:
            if getattr(self, name) > 1.0:
                raise ValueError(f"skill parameter {name} is a probability, got {getattr(self, name)}")

    def scaled(self, g: float) -> SkillProfile:
        """Every parameter times g (g = 0: the expert)."""
        return SkillProfile(**{k: v * g for k, v in asdict(self).items()})

    def plus(self, other: SkillProfile) -> SkillProfile:
        """Both profiles' deviations at once (probabilities capped at 1)."""
        both = {k: v + getattr(other, k) for k, v in asdict(self).items()}
        return SkillProfile(**{k: min(v, 1.0) if k in PROBABILITIES else v for k, v in both.items()})

    def as_dict(self) -> dict[str, float]:
        """The parameters by name (for trajectory metadata)."""
        return {k: float(v) for k, v in asdict(self).items()}


PARAMETERS = tuple(f.name for f in fields(SkillProfile))

# Level 1 of a cohort; level l of L scales every parameter by (L - l) / (L - 1), down to 0 (the expert).
# Tuned so that the heuristic return separates 5 levels on the bundled tasks (bench/cohort_levels.py).
NOVICE = SkillProfile(motor_noise=0.18, tremor=0.4, delay=0.2, overshoot=2.0, hesitation=0.04, wander=0.15, optics=0.6)


def skill_gap(level: int, levels: int) -> float:
    """How far level is from the expert: 1 at level 1 (novice), 0 at level `levels`."""
    if levels < 2:
        raise ValueError(f"a cohort needs at least 2 levels, got {levels}")
    if not 1 <= level <= levels:
        raise ValueError(f"level must be in 1..{levels}, got {level}")
    return (levels - level) / (levels - 1)


def profile_for_level(level: int, levels: int, novice: SkillProfile = NOVICE) -> SkillProfile:
    """The skill profile of a level: level 1 is the novice, level `levels` the expert (all parameters 0)."""
    return novice.scaled(skill_gap(level, levels))
