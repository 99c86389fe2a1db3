"""Behavioural cloning: fit a PPO policy to demonstrated (observation, action) pairs."""

from __future__ import annotations

import numpy as np
import torch
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

from .eager_adam import EagerAdam


def normalize_from_data(venv: VecEnv, observations: np.ndarray) -> None:
    """Set the observation normalisation to the demonstrations' mean and variance (if the venv has one)."""
    if isinstance(venv, VecNormalize) and venv.norm_obs:
        venv.obs_rms.mean = observations.mean(axis=0).astype(np.float64)
        venv.obs_rms.var = observations.var(axis=0).astype(np.float64)
        venv.obs_rms.count = float(len(observations))
        venv.training = False


def behaviour_clone(
    model: BaseAlgorithm,
    venv: VecEnv,
    observations: np.ndarray,
    actions: np.ndarray,
    epochs: int = 20,
    batch_size: int = 256,
    lr: float = 1e-3,
    seed: int = 0,
) -> list[float]:
    """Maximise the policy's log-likelihood of the demonstrated actions; return the mean loss per epoch."""
    normalize_from_data(venv, observations)
    x = venv.normalize_obs(observations) if isinstance(venv, VecNormalize) else observations
    policy = model.policy
    obs_t, _ = policy.obs_to_tensor(x)  # frames channels first, as the policy takes them (it scales them to floats)
    act_t = torch.as_tensor(actions)
    optim = EagerAdam(policy.parameters(), lr=lr)
    rng = np.random.default_rng(seed)
    losses = []
    policy.set_training_mode(True)
    for _ in range(epochs):
        order = rng.permutation(len(act_t))
        total = 0.0
        for start in range(0, len(order), batch_size):
            idx = torch.as_tensor(order[start : start + batch_size])
            batch = {k: v[idx] for k, v in obs_t.items()} if isinstance(obs_t, dict) else obs_t[idx]
            dist = policy.get_distribution(batch)  # the actor alone: a value CNN of its own is not run
            log_prob, entropy = dist.log_prob(act_t[idx]), dist.entropy()
            loss = -log_prob.mean() - 1e-3 * (entropy.mean() if entropy is not None else 0.0)
            optim.zero_grad()
            loss.backward()
            optim.step()
            total += float(loss.detach()) * len(idx)
        losses.append(total / len(act_t))
    policy.set_training_mode(False)
    return losses


def action_accuracy(model: BaseAlgorithm, venv: VecEnv, observations: np.ndarray, actions: np.ndarray) -> float:
    """Share of demonstrated discrete actions the deterministic policy reproduces."""
    x = venv.normalize_obs(observations) if isinstance(venv, VecNormalize) else observations
    predicted, _ = model.predict(x, deterministic=True)
    return float(np.mean(predicted.reshape(-1) == np.asarray(actions).reshape(-1)))
