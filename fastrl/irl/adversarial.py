"""On-policy adversarial IRL on PPO: train the discriminator on each rollout, relabel its rewards."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

from .discriminator import Discriminator


@dataclass
class Transitions:
    """Expert transitions (raw observations) with the actions that produced them."""

    obs: np.ndarray
    next_obs: np.ndarray
    terminal: np.ndarray
    actions: np.ndarray


class AdversarialCallback(BaseCallback):
    """After each PPO rollout: fit the discriminator (expert vs policy) and replace the rollout's rewards."""

    def __init__(self, disc: Discriminator, expert: Transitions, epochs: int = 2, batch_size: int = 256,
                 lr: float = 3e-4, seed: int = 0):
        super().__init__()
        self.disc, self.expert = disc, expert
        self.epochs, self.batch_size = epochs, batch_size
        self.optim = torch.optim.Adam(disc.parameters(), lr=lr)
        self.rng = np.random.default_rng(seed)
        self.stats: dict[str, float] = {}

    def _on_rollout_start(self) -> None:
        self.next_obs, self.terminal, self.env_rewards = [], [], []

    def _normalize(self, obs: np.ndarray) -> np.ndarray:
        env = self.model.get_env()
        return env.normalize_obs(obs) if isinstance(env, VecNormalize) else obs

    def _on_step(self) -> bool:
        new_obs = np.array(self.locals["new_obs"], dtype=np.float32)
        infos, dones = self.locals["infos"], self.locals["dones"]
        terminal = np.zeros(len(dones), np.float32)
        for i, done in enumerate(dones):
            if done:
                new_obs[i] = self._normalize(infos[i]["terminal_observation"][None])[0]
                terminal[i] = 0.0 if infos[i].get("TimeLimit.truncated", False) else 1.0
        self.next_obs.append(new_obs)
        self.terminal.append(terminal)
        self.env_rewards.append(np.array(self.locals["rewards"], np.float32))
        return True

    def _log_pi(self, obs: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
        """log pi(a|s) under the current policy, without gradients."""
        with torch.no_grad():
            _, log_prob, _ = self.model.policy.evaluate_actions(obs, actions)
        return log_prob

    def _on_rollout_end(self) -> None:
        buf = self.model.rollout_buffer
        n, e = buf.buffer_size, buf.n_envs
        obs = torch.as_tensor(buf.observations.reshape(n * e, -1))
        nxt = torch.as_tensor(np.stack(self.next_obs).reshape(n * e, -1))
        term = torch.as_tensor(np.stack(self.terminal).reshape(n * e))
        log_pi = torch.as_tensor(buf.log_probs.reshape(n * e))
        self._fit(obs, nxt, term, log_pi)
        with torch.no_grad():
            learned = self.disc.generator_reward(obs, nxt, term, log_pi).numpy().reshape(n, e)
        bootstrap = buf.rewards - np.stack(self.env_rewards)  # SB3 adds gamma V(s_T) on truncation: keep it
        buf.rewards[:] = learned + bootstrap
        last_obs = torch.as_tensor(self.locals["new_obs"], dtype=torch.float32)
        with torch.no_grad():
            last_values = self.model.policy.predict_values(last_obs)
        buf.compute_returns_and_advantage(last_values=last_values, dones=self.locals["dones"])
        self.stats["irl/learned_reward_policy"] = float(learned.mean())

    def _fit(self, obs, nxt, term, log_pi) -> None:
        """A few epochs of binary cross-entropy: expert transitions 1, policy transitions 0."""
        ex = self.expert
        e_obs = torch.as_tensor(self._normalize(ex.obs), dtype=torch.float32)
        e_nxt = torch.as_tensor(self._normalize(ex.next_obs), dtype=torch.float32)
        e_term = torch.as_tensor(ex.terminal, dtype=torch.float32)
        e_act = torch.as_tensor(ex.actions)
        if self.model.action_space.shape == ():  # Discrete: integer actions
            e_act = e_act.reshape(-1).long()
        e_log_pi = self._log_pi(e_obs, e_act)
        bce = torch.nn.functional.binary_cross_entropy_with_logits
        losses, accs = [], []
        for _ in range(self.epochs):
            for idx in np.array_split(self.rng.permutation(len(obs)), max(1, len(obs) // self.batch_size)):
                j = self.rng.integers(0, len(e_obs), len(idx))
                z_pol = self.disc.logits(obs[idx], nxt[idx], term[idx], log_pi[idx])
                z_exp = self.disc.logits(e_obs[j], e_nxt[j], e_term[j], e_log_pi[j])
                loss = bce(z_pol, torch.zeros_like(z_pol)) + bce(z_exp, torch.ones_like(z_exp))
                self.optim.zero_grad()
                loss.backward()
                self.optim.step()
                losses.append(float(loss.detach()))
                accs.append(0.5 * float((z_pol < 0).float().mean() + (z_exp > 0).float().mean()))
        self.stats.update({"irl/disc_loss": float(np.mean(losses)), "irl/disc_accuracy": float(np.mean(accs))})
        for key, value in self.stats.items():
            self.logger.record(key, value)

