"""A synthetic two-handed trainee: the two-handed expert with hesitation pauses and motor slips over both hands."""

from __future__ import annotations

import numpy as np

from ..agents.expert import ScriptedExpert
from .skill import SkillProfile

PAUSE_STEPS = 8  # mean length of a hesitation pause beyond its first step


class TwoHandTrainee:
    """A discrete policy with `act(obs)` and `reset()`, deterministic given its seed; a zero profile is the expert.

    Of a SkillProfile it uses `motor_noise` (a random movement of either hand instead of the intended one) and
    `hesitation` (idle pauses); the scope-only deviations (tremor, delay, overshoot, wander, optics) do not apply.
    """

    def __init__(self, env, profile: SkillProfile, seed: int = 0):
        u = env.unwrapped
        if u.task_spec.actions.mode != "discrete":
            raise ValueError("synthetic trainees act with discrete actions: set actions.mode: discrete")
        self.env, self.profile, self.seed = u, profile, int(seed)
        self.expert = ScriptedExpert(env)
        self.n = u.action_space.n
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Start an episode: reseed the generator (with `seed` if given) and forget the expert's goal."""
        if seed is not None:
            self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)
        self.pause = 0
        self.expert.reset()

    def act(self, obs=None) -> int:
        """Next discrete action."""
        p = self.profile
        action = int(self.expert.act(obs))  # the expert keeps its goals current even while the trainee idles
        if self.pause > 0:
            self.pause -= 1
            return 0
        if p.hesitation and self.rng.random() < p.hesitation:
            self.pause = int(self.rng.poisson(PAUSE_STEPS))
            return 0
        if p.motor_noise and self.rng.random() < p.motor_noise:
            return int(self.rng.integers(1, self.n))
        return action
