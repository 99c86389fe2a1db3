"""A synthetic trainee: the scripted expert acting through the deviations of a SkillProfile."""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from ..agents.expert import ScriptedExpert
from .skill import SkillProfile

TREMOR_HZ = 2.0  # oscillation of the tremor (control runs at 20 Hz)
FINE = 3.0  # within FINE + lag increments of the goal: move, then wait
PAUSE_STEPS = 8  # mean length of a hesitation pause beyond its first step
SWEEP_STEPS = (5, 20)  # length of a search sweep, or of a committed direct move
SEARCH_MOVES = (1, 2, 3, 4, 9, 10)  # pitch, yaw and light cable: what sweeps the view round
SHAFT_HABIT = (0.0, 2.0)  # (pivot, cable) weights of a view solved by moving the shaft
REACHED = 0.6  # |error| below this many increments: the coordinate is there
NOTICE = 10  # steps at a misjudged goal without completing the avatar before the trainee notices and corrects
DETOUR = 12.0  # increments of pitch and yaw between a detour's wrong place and the right one
BUMP_STEPS = 40  # most steps a bump pushes the scope in (the first contact stops it)


class Acting:
    """What every synthetic trainee holds: the env, its profile and seed, and the scripted expert it acts through."""

    def __init__(self, env, profile: SkillProfile, seed: int = 0):
        u = env.unwrapped
        if u.task_spec.actions.mode != "discrete":
            raise ValueError("synthetic trainees act with discrete actions: set actions.mode: discrete")
        self.env, self.profile, self.seed = u, profile, int(seed)
        self.expert = ScriptedExpert(env)

    def reseed(self, seed: int | None) -> None:
        """A fresh random generator from `seed` if given, else from the trainee's own."""
        if seed is not None:
            self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)

    def paused(self) -> bool:
        """Whether the trainee holds still this step: a pause under way, or a hesitation that starts one."""
        if self.pause > 0:
            self.pause -= 1
            return True
        if self.profile.hesitation and self.rng.random() < self.profile.hesitation:
            self.pause = int(self.rng.poisson(PAUSE_STEPS))
            return True
        return False


class Trainee(Acting):
    """A policy with `act(obs)` and `reset()`; deterministic given its seed; a zero profile is the expert."""

    def __init__(self, env, profile: SkillProfile, seed: int = 0):
        super().__init__(env, profile, seed)
        self.optics_weights = (self.expert.pivot_weight, self.expert.cable_weight)
        self.steps = self.expert.steps  # size of one increment of each coordinate
        self.lag = int(round(profile.delay * self.env.task_spec.episode.control_hz))
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Start an episode: reseed the generator (with `seed` if given) and forget all state."""
        self.reseed(seed)
        self.phase = self.rng.uniform(0.0, 2.0 * math.pi, 2)
        self._clear()

    def _clear(self) -> None:
        """Forget the episode's state (goal, perception history, pauses, sweeps)."""
        self.expert.reset()
        self.history = deque(maxlen=self.lag + 1)
        self.pause = self.sweep = self.direct = self.extra = self.wait = 0
        self.sweep_action = self.last = 0
        self.overshot, self.subtask = set(), -1
        self.shaken = np.zeros(2)  # increments of pitch and yaw made by the tremor so far
        self.misjudged = np.zeros(5)  # the trainee's error in judging the goal (depth, aim, horizon)
        self.waypoint = np.zeros(5)  # a wrong place headed for first (a detour), dropped once there
        self.settled = 0  # steps spent at the perceived goal
        self.push = 0  # steps left of pushing the scope in (a bump)
        self.cycle, self.dither = np.full(2, -1.0), np.zeros(2)

    def act(self, obs=None) -> int:
        """Next discrete action."""
        u, p = self.env, self.profile
        if u.steps == 0 and self.history:  # a new episode without reset(): drop the old one's state
            self._clear()
        self.history.append((u.portal_coordinates(), min(u.done_count, len(u.t_pos) - 1)))
        if self.paused():
            return 0
        if self.extra > 0:
            self.extra -= 1
            return self._slip(self.last)
        if self.push > 0 or (p.bump and self.rng.random() < p.bump):
            return self._bump()
        if self.wait > 0:  # waiting to see the effect of a fine move
            self.wait -= 1
            return 0
        action = self._tremor()
        if action is None:
            action = self._search()
        if action is None:
            q, k = self.history[0]  # what the trainee perceives: `lag` steps old
            action = self._direct(q, k)
        return self._slip(action)

    def _tremor(self) -> int | None:
        """A pitch or yaw increment that follows the tremor's oscillation (None: the hand is where it shakes to)."""
        a = self.profile.tremor
        if not a:
            return None
        cycles = self.env.steps * self.env.dt * TREMOR_HZ + self.phase / (2.0 * math.pi)
        if np.any(np.floor(cycles) != self.cycle):  # a new period: draw its rounding (graded, not stepped, in a)
            self.cycle, self.dither = np.floor(cycles), self.rng.random(2)
        want = np.floor(a * np.sin(2.0 * math.pi * cycles) + self.dither)
        gap = want - self.shaken
        c = int(np.argmax(np.abs(gap)))
        if gap[c] == 0:
            return None
        self.shaken[c] += np.sign(gap[c])
        return 1 + 2 * c + (0 if gap[c] > 0 else 1)

    def _search(self) -> int | None:
        """A random sweep while the avatar is out of view (None: move straight toward the goal)."""
        p, s = self.profile, self.env.state
        if self.sweep > 0 and s.contacts:  # bumped into the dome: the sweep stops
            self.sweep = 0
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
        """The expert's move on the perceived pose, carried past the goal by overshoot, waited on when fine."""
        p = self.profile
        if self.subtask != k:
            self._new_subtask(k)
        err = self.expert.error(q, k) + self.misjudged + self.waypoint
        if self.profile.tremor:  # the trainee aims through the shake, not at correcting it
            err[:2] += self.shaken * self.steps[:2]
        action = int(self.expert.to_action(err))
        if self.pause > 0:  # a new avatar: plan before the first move
            self.pause -= 1
            return 0
        if self.misjudged.any() or self.waypoint.any():
            action = self._judged(action)
        if p.overshoot and self.last and action != self.last:
            c = (self.last - 1) // 2
            if c not in self.overshot and abs(err[c]) < REACHED * self.steps[c]:
                self.overshot.add(c)  # once per coordinate and subtask; then corrections are careful
                n = int(self.rng.poisson(p.overshoot))
                if n:
                    self.extra = n - 1
                    return self.last
        self.last = action
        c = (action - 1) // 2
        if self.lag and action and abs(err[c]) < (FINE + self.lag) * self.steps[c]:
            self.wait = self.lag  # near the goal (nearer than the lag can carry): move, then wait to see the result
        return action

    def _new_subtask(self, k: int) -> None:
        """Per subtask: may overshoot again; with poor optics, may solve the view by moving the shaft; plans,
        misjudges the goal, heads for a wrong place first or pushes in until it touches, as the profile says."""
        p, rng = self.profile, self.rng
        self.subtask, self.overshot = k, set()
        shaft = p.optics and rng.random() < p.optics
        self.expert.pivot_weight, self.expert.cable_weight = SHAFT_HABIT if shaft else self.optics_weights
        if p.idle:
            self.pause = int(rng.poisson(p.idle * self.env.task_spec.episode.control_hz))
        sd = np.array([p.aim, p.aim, p.depth, p.horizon, 0.0])
        self.misjudged = rng.normal(0.0, 1.0, 5) * sd * self.steps if sd.any() else np.zeros(5)
        self.waypoint, self.settled = np.zeros(5), 0
        if p.detour and rng.random() < p.detour:
            turn = rng.uniform(0.0, 2.0 * math.pi)
            self.waypoint[:2] = DETOUR * np.array([math.cos(turn), math.sin(turn)]) * self.steps[:2]

    def _bump(self) -> int:
        """Push the scope in until it touches something (or BUMP_STEPS pass); the goal then draws it back."""
        if self.push == 0:
            self.push = BUMP_STEPS
        self.push = 0 if self.env.state.contacts else self.push - 1
        return 5 if self.push else 0

    def _judged(self, action: int) -> int:
        """Correct a misjudged goal: a wrong place is left once reached; a misjudged one is halved after NOTICE
        steps there without the avatar completing."""
        if action:
            self.settled = 0
            return action
        self.settled += 1
        if self.waypoint.any():
            self.waypoint[:], self.settled = 0.0, 0
        elif self.settled >= NOTICE:
            self.misjudged *= 0.5
            self.misjudged[np.abs(self.misjudged) < REACHED * self.steps] = 0.0
            self.settled = 0
        return action

    def _slip(self, action: int) -> int:
        """Motor noise: sometimes a random movement instead of the intended action; a slow trainee waits instead
        of some moves, a dithering one goes the opposite way."""
        return paced(self.profile, self.rng, action, 11)


def paced(p: SkillProfile, rng: np.random.Generator, action: int, n: int) -> int:
    """An intended discrete action as moved: a random one of n (motor noise), none (slowness) or the opposite
    movement (dither); a no-op stays one."""
    if p.motor_noise and rng.random() < p.motor_noise:
        return int(rng.integers(1, n))
    if action and p.slowness and rng.random() < p.slowness:
        return 0
    if action and p.dither and rng.random() < p.dither:
        return int(action + 1 if (action - 1) % 2 == 0 else action - 1)
    return int(action)
