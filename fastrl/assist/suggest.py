"""Path suggestion: roll the trained policy out from the trainee's state in a scratch copy of the task."""

from __future__ import annotations

import time
from dataclasses import dataclass

import mujoco
import numpy as np
import torch

from ..env.fast_env import FastEnv
from ..env.sensing import RAY_GROUPS
from ..spec.models import TaskSpec


@dataclass
class Suggestion:
    """A suggested tip path from one state, and whether it reaches the next avatar."""

    tip: np.ndarray  # (n, 3) tip positions, the start state first
    portal: np.ndarray  # (n, 5) portal coordinates along the path
    aim: np.ndarray  # (n, 3) where the optical axis meets the scene (view centre); NaN: meets nothing
    reached: bool  # the policy completed the current subtask within the horizon
    reached_at: int | None  # index into tip where the subtask completed
    start_subtask: int
    ms: float  # wall time to compute


class Suggester:
    """Rolls a policy (batch obs -> actions) out for `horizon_s` seconds from a live env's state; never touches it."""

    def __init__(self, spec: TaskSpec, policy, horizon_s: float = 3.0):
        torch.set_num_threads(1)  # one sample per call: intra-op threads only add contention (35 ms -> 0.2 ms here)
        self.scratch = FastEnv(spec)
        self.scratch.reset(seed=0)
        self.policy = policy
        self.horizon = max(1, int(round(horizon_s * spec.episode.control_hz)))
        self._pnt, self._vec, self._geom = np.zeros(3), np.zeros(3), np.zeros(1, np.int32)
        self._exclude = self.scratch.model.body("scope_shaft").id

    def suggest(self, live: FastEnv) -> Suggestion:
        """The policy's path from the live env's current state."""
        t0 = time.perf_counter()
        env = self.scratch
        env.copy_state_from(live)
        start = env.done_count
        obs = env.observation()
        tips, coords, aims, reached_at = [env.state.tip_pos], [env.portal_coordinates()], [self._aim()], None
        for _ in range(self.horizon):
            action = self.policy(obs[None])[0]
            obs, _, term, _, _ = env.step(action)
            tips.append(env.state.tip_pos)
            coords.append(env.portal_coordinates())
            aims.append(self._aim())
            if reached_at is None and env.done_count > start:
                reached_at = len(tips) - 1
            if term:
                break
        ms = 1000.0 * (time.perf_counter() - t0)
        return Suggestion(
            np.array(tips), np.array(coords), np.array(aims), reached_at is not None, reached_at, start, ms
        )

    def _aim(self) -> tuple:
        """Where the scratch camera's optical axis meets the scene (NaN if it meets nothing)."""
        env = self.scratch
        s = env.state
        self._pnt[:], self._vec[:] = s.cam_pos, s.cam_fwd
        dist = mujoco.mj_ray(env.model, env.data, self._pnt, self._vec, RAY_GROUPS, 1, self._exclude, self._geom)
        if dist < 0:
            return (np.nan,) * 3
        return tuple(self._pnt + dist * self._vec)
