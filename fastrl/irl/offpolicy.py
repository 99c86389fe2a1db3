"""Off-policy adversarial IRL on SAC: the discriminator trains between rollouts, rewards are relabelled on sampling.

Two switches, for ablations: spectral normalisation of the discriminator (a `Discriminator` option) and
`current_rollout`, which trains the discriminator only on the transitions of the latest rollout
(train_freq x n_envs) instead of on samples of the whole replay buffer. With `every`, the discriminator fits
once per that many env steps instead, and its "current rollout" is everything collected since the last fit:
SAC schedules with short rollouts then do not pay a discriminator fit per env step.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from stable_baselines3.common.buffers import ReplayBuffer
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.type_aliases import ReplayBufferSamples

from .discriminator import augment
from .fitting import DiscriminatorFit, Transitions, make_batch
from .generator import log_prob, normalize_obs, transitions_batch


class RelabelingReplayBuffer(ReplayBuffer):
    """A replay buffer whose sampled rewards come from `relabel(samples)` when it is set."""

    relabel: Callable[[ReplayBufferSamples], torch.Tensor] | None = None

    def _get_samples(self, batch_inds: np.ndarray, env=None) -> ReplayBufferSamples:
        samples = super()._get_samples(batch_inds, env)
        return samples if self.relabel is None else samples._replace(rewards=self.relabel(samples))

    def latest(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """(positions, env indices) of the last k/n_envs steps of every env, newest last."""
        steps = max(1, k // self.n_envs)
        pos = (self.pos - steps + np.arange(steps)) % self.buffer_size
        if not self.full:
            pos = pos[pos < self.pos]
        return np.repeat(pos, self.n_envs), np.tile(np.arange(self.n_envs), len(pos))


class OffPolicyAdversarialCallback(BaseCallback):
    """Before each SAC update: fit the discriminator on current-rollout (or replay) samples vs expert samples."""

    def __init__(
        self,
        fit: DiscriminatorFit,
        expert: Transitions,
        *,
        current_rollout: bool = True,
        steps: int = 4,
        every: int = 0,
    ):
        super().__init__()
        self.fit, self.disc, self.expert = fit, fit.disc, expert
        self.current_rollout, self.n_steps = current_rollout, steps
        self.every, self.last_fit = every, 0
        self.stats: dict[str, float] = {}
        self.last_policy_rows: tuple[np.ndarray, np.ndarray] | None = None

    def _on_training_start(self) -> None:
        buf = self.model.replay_buffer
        if not isinstance(buf, RelabelingReplayBuffer):
            raise TypeError("off-policy IRL needs replay_buffer_class=RelabelingReplayBuffer")
        buf.relabel = self.relabel

    def _on_step(self) -> bool:
        return True

    def _policy_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """Buffer rows the discriminator sees as policy samples: the latest rollout, or uniform over the buffer."""
        buf, model = self.model.replay_buffer, self.model
        k = model.num_timesteps - self.last_fit if self.every else model.train_freq.frequency * buf.n_envs
        k = min(k, buf.buffer_size * buf.n_envs)
        if self.current_rollout:
            return buf.latest(k)
        size = buf.buffer_size if buf.full else buf.pos
        n = max(k, self.fit.batch_size * self.n_steps)
        return self.fit.rng.integers(0, size, n), self.fit.rng.integers(0, buf.n_envs, n)

    def _on_rollout_end(self) -> None:
        now = self.model.num_timesteps
        if now < self.model.learning_starts or (self.every and now - self.last_fit < self.every):
            return
        buf = self.model.replay_buffer
        pos, env_idx = self.last_policy_rows = self._policy_rows()
        self.last_fit = now
        obs = normalize_obs(self.model, buf.observations[pos, env_idx])
        nxt = normalize_obs(self.model, buf.next_observations[pos, env_idx])
        term = buf.dones[pos, env_idx] * (1 - buf.timeouts[pos, env_idx])
        obs_t = torch.as_tensor(obs, dtype=torch.float32)
        lp = log_prob(self.model, obs_t, torch.as_tensor(buf.actions[pos, env_idx], dtype=torch.float32))
        policy = make_batch(obs_t, nxt, term, lp, self.disc.absorbing)
        # only as many expert rows as the fit draws: normalising and scoring all of them every rollout costs more
        rows = self.fit.rng.integers(0, len(self.expert.obs), self.fit.batch_size * self.n_steps)
        expert = transitions_batch(self.model, self.expert, self.disc, rows)
        self.stats.update(self.fit.steps(policy, expert, self.n_steps))
        self.stats.update(self.fit.reward_stats(policy, expert))
        for key, value in self.stats.items():
            self.logger.record(key, value)

    def relabel(self, samples: ReplayBufferSamples) -> torch.Tensor:
        """The current discriminator's reward for sampled transitions (SAC adds its own entropy term)."""
        with torch.no_grad():
            s, s2 = augment(samples.observations.float()), augment(samples.next_observations.float())
            done = samples.dones.float().reshape(-1)
            r = self.disc.generator_reward(s, s2, done, torch.zeros_like(done), entropy=False)
            return (r + self.disc.terminal_bonus(done)).reshape(-1, 1)
