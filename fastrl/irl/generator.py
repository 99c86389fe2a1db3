"""What the discriminator needs from a stable-baselines3 generator: normalised observations and log pi(a|s)."""

from __future__ import annotations

import numpy as np
import torch
from stable_baselines3 import SAC
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecNormalize

from .discriminator import Discriminator
from .fitting import Batch, Transitions, make_batch


def normalize_obs(model: BaseAlgorithm, obs: np.ndarray) -> np.ndarray:
    """Observations as the policy sees them (the training env's running normalisation, if any)."""
    env = model.get_env()
    return env.normalize_obs(obs) if isinstance(env, VecNormalize) else obs


def log_prob(model: BaseAlgorithm, obs: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
    """log pi(a|s) of given actions under the current policy (SAC: the squashed Gaussian), without gradients."""
    with torch.no_grad():
        if isinstance(model, SAC):
            mean, log_std, _ = model.actor.get_action_dist_params(obs)
            dist = model.actor.action_dist.proba_distribution(mean, log_std)
            return dist.log_prob(actions.clamp(-1.0 + 1e-6, 1.0 - 1e-6))
        if model.action_space.shape == ():  # Discrete: integer actions
            actions = actions.reshape(-1).long()
        _, lp, _ = model.policy.evaluate_actions(obs, actions)
        return lp


def original_obs(model: BaseAlgorithm, obs: np.ndarray) -> np.ndarray:
    """Undo the training env's observation normalisation (exact unless a value was clipped)."""
    env = model.get_env()
    return env.unnormalize_obs(obs) if isinstance(env, VecNormalize) else obs


def current_original_obs(model: BaseAlgorithm, latest: np.ndarray) -> np.ndarray:
    """The training envs' `latest` observations (after any automatic reset) before normalisation."""
    env = model.get_env()
    return env.get_original_obs() if isinstance(env, VecNormalize) else latest


def transitions_batch(
    model: BaseAlgorithm, data: Transitions, disc: Discriminator, rows: np.ndarray | None = None
) -> Batch:
    """Transitions with raw observations (or only `rows` of them) as a discriminator batch: normalised as the
    policy sees them now, log pi(a|s) under the current policy."""
    if rows is not None:
        data = data.take(rows)
    obs = torch.as_tensor(normalize_obs(model, data.obs), dtype=torch.float32)
    nxt = normalize_obs(model, data.next_obs)
    lp = log_prob(model, obs, torch.as_tensor(data.actions, dtype=torch.float32))
    return make_batch(obs, nxt, data.terminal, lp, disc.absorbing)
