"""Keep a cloned PPO actor near the demonstrations: behavioural-cloning steps after every PPO update (as DAPG)."""

from __future__ import annotations

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

BATCH = 256  # demonstrated pairs per anchoring step


class CloneAnchor(BaseCallback):
    """After each PPO update (at the next rollout's start), `steps` minibatches that maximise the demonstrated
    actions' log-likelihood on the policy's own optimizer: the adversarial reward moves the clone, they hold it."""

    def __init__(self, obs: np.ndarray, actions: np.ndarray, *, steps: int, seed: int):
        super().__init__()
        self.raw_obs, self.actions, self.steps = obs, torch.as_tensor(actions), steps
        self.rng = np.random.default_rng(seed)

    def _on_rollout_start(self) -> None:
        if self.model.num_timesteps == 0:  # no update yet: the clone as fitted
            return
        env = self.model.get_env()
        policy = self.model.policy
        normalize = isinstance(env, VecNormalize) and env.norm_obs
        policy.set_training_mode(True)
        for _ in range(self.steps):
            idx = self.rng.integers(0, len(self.raw_obs), BATCH)
            raw = self.raw_obs[idx]
            obs, _ = policy.obs_to_tensor(env.normalize_obs(raw) if normalize else raw)  # frames: channels first
            log_prob = policy.get_distribution(obs).log_prob(self.actions[torch.as_tensor(idx)])
            policy.optimizer.zero_grad()
            (-log_prob.mean()).backward()
            torch.nn.utils.clip_grad_norm_(policy.parameters(), self.model.max_grad_norm)
            policy.optimizer.step()
        policy.set_training_mode(False)

    def _on_step(self) -> bool:
        return True
