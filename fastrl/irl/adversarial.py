"""On-policy adversarial IRL on PPO: fit the discriminator on each rollout, then relabel its rewards."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

from .discriminator import augment
from .fitting import DiscriminatorFit, Transitions, make_batch
from .generator import current_original_obs, normalize_obs, original_obs, transitions_batch
from .history import PolicyHistory
from .ranking import RankedRollouts, support_loss
from .scaling import ReturnScale


class AdversarialCallback(BaseCallback):
    """After each PPO rollout: fit the discriminator (expert vs policy, by `fit`) and replace the rollout's rewards.

    With `history` > 0, each fit's policy side is the rollout plus as many transitions drawn from a reservoir of
    that many earlier ones (raw observations, normalised and scored under the current policy when drawn).
    With `scale_reward` (the spec's default: AIRL yes, GAIL no), the generator's learned reward is divided by the
    running spread of its discounted return. With `ranked` rollouts, each discriminator step adds `ranking_weight`
    times their ranking loss on shaped AIRL's r_psi, and with `support_spread` the demonstrated states' support loss.
    With `motion` (raw observations, next observations -> each transition's motion log-density below the
    demonstrations' best), it keeps the last rollout to weigh that term against the learned reward (motion_scale)."""

    def __init__(
        self,
        fit: DiscriminatorFit,
        expert: Transitions,
        *,
        epochs: int = 2,
        seed: int = 0,
        history: int = 0,
        scale_reward: bool = False,
        ranked: RankedRollouts | None = None,
        ranking_weight: float = 0.0,
        support_spread: float = 0.0,
        motion: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
    ):
        super().__init__()
        self.fit, self.disc, self.expert, self.n_epochs = fit, fit.disc, expert, epochs
        self.history = PolicyHistory(history, seed) if history else None
        self.scale_reward = scale_reward
        self.scale: ReturnScale | None = None
        self.stats: dict[str, float] = {}
        self.ranked, self.ranking_weight = ranked, ranking_weight
        self.ranking_rng = np.random.default_rng(seed + 1)
        self.support_spread = support_spread
        self._frozen_states: torch.Tensor | None = None
        self.motion, self.last_rollout = motion, None

    def _on_rollout_start(self) -> None:
        self.next_obs, self.terminal, self.env_rewards, self.dones = [], [], [], []
        if self.history is not None:  # SB3 has not stepped yet: its _last_obs is the rollout's first observation
            self.raw_obs = [np.array(current_original_obs(self.model, self.model._last_obs), np.float32)]
            self.raw_next = []

    def _on_step(self) -> bool:
        new_obs = np.array(self.locals["new_obs"], dtype=np.float32)
        infos, dones = self.locals["infos"], self.locals["dones"]
        terminal = np.zeros(len(dones), np.float32)
        for i, done in enumerate(dones):
            if done:  # VecNormalize has already normalised the terminal observation
                new_obs[i] = infos[i]["terminal_observation"]
                terminal[i] = 0.0 if infos[i].get("TimeLimit.truncated", False) else 1.0
        self.next_obs.append(new_obs)
        self.terminal.append(terminal)
        self.dones.append(np.array(dones, bool))
        self.env_rewards.append(np.array(self.locals["rewards"], np.float32))
        if self.history is not None:
            raw_new = np.array(current_original_obs(self.model, self.locals["new_obs"]), np.float32)
            self.raw_obs.append(raw_new)
            raw_next = raw_new.copy()
            raw_next[dones] = original_obs(self.model, new_obs[dones])
            self.raw_next.append(raw_next)
        return True

    def _with_history(self, policy, term: np.ndarray):
        """The rollout's batch plus as many rows from the history; then the rollout joins the history."""
        buf = self.model.rollout_buffer
        n = len(term)
        raw = Transitions(
            np.stack(self.raw_obs[:-1]).reshape(n, -1),
            np.stack(self.raw_next).reshape(n, -1),
            term,
            buf.actions.reshape(n, *buf.actions.shape[2:]),
        )
        if len(self.history):
            policy = policy.cat(transitions_batch(self.model, self.history.sample(n), self.disc))
        self.history.add(raw)
        return policy

    def _ranked_states(self):
        """The ranking rollouts' states as the discriminator sees them now: once for all while the observation
        normalisation is frozen (a cloned generator keeps the clone's), else again after each rollout."""
        env = self.model.get_env()
        frozen = not isinstance(env, VecNormalize) or not env.training
        if frozen and self._frozen_states is not None:
            return self._frozen_states
        states = self.ranked.states(lambda o: normalize_obs(self.model, o))
        self._frozen_states = states if frozen else None
        return states

    def _ranking_loss(self, states: torch.Tensor, shown: torch.Tensor) -> torch.Tensor:
        """The ranked rollouts' loss plus the demonstrated states' support loss."""
        rng = self.ranking_rng
        return self.ranked.loss(self.disc, states, rng) + support_loss(self.disc, shown, rng, self.support_spread)

    def motion_scale(self) -> float:
        """The spread of the generator's learned reward over its last rollout divided by that of the rollout's motion
        log-density: what a nat of motion weighs in the learned reward (0 before the first rollout)."""
        if self.last_rollout is None:
            return 0.0
        obs, nxt, learned = self.last_rollout
        return float(learned.std() / max(float(self.motion(obs, nxt).std()), 1e-9))

    def value_units(self) -> float:
        """What a unit of learned reward is in the rewards the generator's critic learned from: 1 over the return
        scaling's last divisor (1 unscaled)."""
        return 1.0 if self.scale is None else float(1.0 / np.sqrt(self.scale.stats.var + self.scale.epsilon))

    def _on_rollout_end(self) -> None:
        buf = self.model.rollout_buffer
        n, e = buf.buffer_size, buf.n_envs
        obs, nxt = buf.observations.reshape(n * e, -1), np.stack(self.next_obs).reshape(n * e, -1)
        term, log_pi = np.stack(self.terminal).reshape(n * e), buf.log_probs.reshape(n * e)
        rollout = make_batch(obs, nxt, term, log_pi, self.disc.absorbing)
        policy = rollout if self.history is None else self._with_history(rollout, term)
        expert = transitions_batch(self.model, self.expert, self.disc)
        if self.ranked is not None:
            states = self._ranked_states()
            shown = expert.s[expert.s[:, -1] == 0]
            self.fit.ranking = lambda: self.ranking_weight * self._ranking_loss(states, shown)
        self.stats.update(self.fit.epochs(policy, expert, self.n_epochs))
        self.stats.update(self.fit.reward_stats(rollout, expert))
        with torch.no_grad():
            s, s2 = augment(torch.as_tensor(obs)), augment(torch.as_tensor(nxt))
            t, lp = torch.as_tensor(term), torch.as_tensor(log_pi)
            reward = self.disc.generator_reward(s, s2, t, lp) + self.disc.terminal_bonus(t)
            learned = reward.numpy().reshape(n, e)
        self.stats["irl/generator_reward"] = float(learned.mean())
        if self.motion is not None:  # raw copies now: the buffer and the normalisation move on
            self.last_rollout = np.array(original_obs(self.model, obs)), original_obs(self.model, nxt), learned.ravel()
        if self.scale_reward:
            self.scale = self.scale or ReturnScale(e, self.model.gamma)
            learned = self.scale(learned, np.stack(self.dones))
            self.stats["irl/generator_reward_scale"] = float(np.sqrt(self.scale.stats.var))
        bootstrap = buf.rewards - np.stack(self.env_rewards)  # SB3 adds gamma V(s_T) on truncation: keep it
        buf.rewards[:] = learned + bootstrap
        last_obs = torch.as_tensor(self.locals["new_obs"], dtype=torch.float32)
        with torch.no_grad():
            last_values = self.model.policy.predict_values(last_obs)
        buf.compute_returns_and_advantage(last_values=last_values, dones=self.locals["dones"])
        for key, value in self.stats.items():
            self.logger.record(key, value)
