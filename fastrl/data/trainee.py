"""A synthetic trainee: the scripted expert acting through the deviations of a SkillProfile."""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from ..agents.expert import ScriptedExpert
from .skill import SkillProfile

TREMOR_HZ = 5.0                                   # oscillation of the tremor (control runs at 20 Hz)
TREMOR_AXES = np.array([1.0, 1.0, 0.0, 1.0, 0.0])  # the hand shakes the shaft: pitch, yaw, roll
PAUSE_STEPS = 8                                   # mean length of a hesitation pause beyond its first step
SWEEP_STEPS = (5, 20)                             # length of a search sweep, or of a committed direct move
SEARCH_MOVES = (1, 2, 3, 4, 9, 10)                # pitch, yaw and light cable: what sweeps the view round
OPTICS_CABLE_WEIGHT = 2.0                         # cable cost in the view solution at optics = 1
EXPERT_CABLE_WEIGHT = 0.005
REACHED = 0.6                                     # |error| below this many increments: the coordinate is there


class Trainee:
    """A policy with `act(obs)` and `reset()`; deterministic given its seed; a zero profile is the expert."""

    def __init__(self, env, profile: SkillProfile, seed: int = 0):
        u = env.unwrapped
        if u.task_spec.actions.mode != "discrete":
            raise ValueError("synthetic trainees act with discrete actions: set actions.mode: discrete")
        self.env, self.profile, self.seed = u, profile, int(seed)
        pivot = ScriptedExpert(env).pivot_weight
        self.expert = ScriptedExpert(env, pivot_weight=pivot * (1.0 - profile.optics),
                                     cable_weight=EXPERT_CABLE_WEIGHT + OPTICS_CABLE_WEIGHT * profile.optics)
        self.steps = self.expert.steps  # size of one increment of each coordinate
        self.lag = int(round(profile.delay * u.task_spec.episode.control_hz))
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Start an episode: reseed the generator (with `seed` if given) and forget all state."""
        if seed is not None:
            self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)
        self.phase = self.rng.uniform(0.0, 2.0 * math.pi, 5)
        self._clear()

    def _clear(self) -> None:
        """Forget the episode's state (goal, perception history, pauses, sweeps)."""
        self.expert.reset()
        self.history = deque(maxlen=self.lag + 1)
        self.pause = self.sweep = self.direct = self.extra = 0
        self.sweep_action = self.last = 0
        self.overshot, self.overshot_for = set(), -1

    def act(self, obs=None) -> int:
        """Next discrete action."""
        u, p = self.env, self.profile
        if u.steps == 0 and self.history:  # a new episode without reset(): drop the old one's state
            self._clear()
        self.history.append((u.portal_coordinates(), min(u.done_count, len(u.t_pos) - 1)))
        if self.pause > 0:
            self.pause -= 1
            return 0
        if p.hesitation and self.rng.random() < p.hesitation:
            self.pause = int(self.rng.poisson(PAUSE_STEPS))
            return 0
        if self.extra > 0:
            self.extra -= 1
            return self._slip(self.last)
        action = self._search()
        if action is None:
            q, k = self.history[0]  # what the trainee perceives: `lag` steps old
            action = self._direct(q, k)
        return self._slip(action)

    def _search(self) -> int | None:
        """A random sweep while the avatar is out of view (None: move straight toward the goal)."""
        p, s = self.profile, self.env.state
        if self.sweep > 0:
            self.sweep -= 1
            return self.sweep_action
        if not p.wander or s.centring < 0.5 * s.fov:
            return None
        if self.direct > 0:
            self.direct -= 1
            return None
        if self.rng.random() < p.wander:
            self.sweep = int(self.rng.integers(*SWEEP_STEPS)) - 1
            self.sweep_action = int(self.rng.choice(SEARCH_MOVES))
            self.last = self.sweep_action
            return self.sweep_action
        self.direct = int(self.rng.integers(*SWEEP_STEPS)) - 1
        return None

    def _direct(self, q: np.ndarray, k: int) -> int:
        """The expert's move on the perceived pose, shaken by tremor, carried past the goal by overshoot."""
        p = self.profile
        err = self.expert.error(q, k)
        if p.tremor:
            t = self.env.steps * self.env.dt
            err = err + p.tremor * self.steps * TREMOR_AXES * np.sin(2.0 * math.pi * TREMOR_HZ * t + self.phase)
        action = int(self.expert.to_action(err))
        if self.overshot_for != k:
            self.overshot, self.overshot_for = set(), k
        if p.overshoot and self.last and action != self.last:
            c = (self.last - 1) // 2
            if c not in self.overshot and abs(err[c]) < REACHED * self.steps[c]:
                self.overshot.add(c)  # once per coordinate and subtask; then corrections are careful
                n = int(self.rng.poisson(p.overshoot))
                if n:
                    self.extra = n - 1
                    return self.last
        self.last = action
        return action

    def _slip(self, action: int) -> int:
        """Motor noise: sometimes a random movement instead of the intended action."""
        p = self.profile.motor_noise
        if p and self.rng.random() < p:
            return int(self.rng.integers(1, 11))
        return int(action)
