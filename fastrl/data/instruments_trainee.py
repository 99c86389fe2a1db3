"""A synthetic trainee of tasks with instruments: their expert with hesitation pauses and motor slips on each."""

from __future__ import annotations

import numpy as np

from ..agents.expert import ScriptedExpert
from .skill import SkillProfile
from .trainee import paced

PAUSE_STEPS = 8  # mean length of a hesitation pause beyond its first step


class TwoInstrumentTrainee:
    """A discrete policy with `act(obs)` and `reset()`, deterministic given its seed; a zero profile is the expert.

    Of a SkillProfile it uses the deviations of the scope's and the instruments' actions: `motor_noise` (a random
    movement instead of the intended one), `hesitation` and `idle` (pauses), `slowness` and `dither`; the scope's
    own (tremor, delay, overshoot, wander, optics, depth, aim, horizon, detour, bump) do not apply.
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
        self.pause, self.subtask = 0, -1
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
        if p.idle and self.subtask != self.env.done_count:  # a new target: plan before the first move
            self.subtask = self.env.done_count
            self.pause = int(self.rng.poisson(p.idle * self.env.task_spec.episode.control_hz))
            if self.pause:
                self.pause -= 1
                return 0
        return paced(p, self.rng, action, self.n)
