"""Scale a learned reward by the running spread of its discounted return, as VecNormalize does for env rewards."""

from __future__ import annotations

import numpy as np
from stable_baselines3.common.running_mean_std import RunningMeanStd


class ReturnScale:
    """Divides rewards by the running standard deviation of each env's discounted return (no centring), clipped."""

    def __init__(self, n_envs: int, gamma: float, clip: float = 10.0, epsilon: float = 1e-8):
        self.gamma, self.clip, self.epsilon = gamma, clip, epsilon
        self.returns = np.zeros(n_envs)
        self.stats = RunningMeanStd(shape=())

    def __call__(self, rewards: np.ndarray, dones: np.ndarray) -> np.ndarray:
        """Update the statistics with a rollout's (steps, envs) rewards and episode ends; return them scaled."""
        for r, done in zip(rewards, dones):
            self.returns = self.returns * self.gamma + r
            self.stats.update(self.returns)
            self.returns[done] = 0.0
        return np.clip(rewards / np.sqrt(self.stats.var + self.epsilon), -self.clip, self.clip).astype(rewards.dtype)
