"""A synthetic trainee of tasks with instruments: their expert with hesitation pauses and motor slips on each."""

from __future__ import annotations

from .skill import SkillProfile
from .trainee import Acting, paced


class TwoInstrumentTrainee(Acting):
    """A discrete policy with `act(obs)` and `reset()`, deterministic given its seed; a zero profile is the expert.

    Of a SkillProfile it uses the deviations of the scope's and the instruments' actions: `motor_noise` (a random
    movement instead of the intended one), `hesitation` and `idle` (pauses), `slowness` and `dither`; the scope's
    own (tremor, delay, overshoot, wander, optics, depth, aim, horizon, detour, bump) do not apply.
    """

    def __init__(self, env, profile: SkillProfile, seed: int = 0):
        super().__init__(env, profile, seed)
        self.n = self.env.action_space.n
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Start an episode: reseed the generator (with `seed` if given) and forget the expert's goal."""
        self.reseed(seed)
        self.pause, self.subtask = 0, -1
        self.expert.reset()

    def act(self, obs=None) -> int:
        """Next discrete action."""
        p = self.profile
        action = int(self.expert.act(obs))  # the expert keeps its goals current even while the trainee idles
        if self.paused():
            return 0
        if p.idle and self.subtask != self.env.done_count:  # a new target: plan before the first move
            self.subtask = self.env.done_count
            self.pause = int(self.rng.poisson(p.idle * self.env.task_spec.episode.control_hz))
            if self.pause:
                self.pause -= 1
                return 0
        return paced(p, self.rng, action, self.n)
