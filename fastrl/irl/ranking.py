"""A ranking prior for shaped AIRL's r_psi from automatically ranked demonstrations (D-REX, Brown et al. 2019).

The scripted expert is rolled out with its actions replaced by random ones at several rates (each held for a few
steps if asked, so that the scope also wanders into the walls): more noise, worse behaviour. Each discriminator
step then asks r_psi to sum higher over a snippet of a less noisy rollout than over the same time steps of a
noisier one (Bradley-Terry), so the reward also orders behaviour far from the expert's.
A rollout that ended (the task done) continues in the absorbing state up to the time limit.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from ..agents.expert import ScriptedExpert
from ..data.replay import rollout_trajectory
from .discriminator import Discriminator, absorbing_states, augment


def noisy_expert_rollout(
    env, expert: ScriptedExpert, noise: float, seed: int, repeat: int = 1
) -> tuple[np.ndarray, bool]:
    """Raw observations (T+1, d) of the expert whose action is replaced, with probability `noise`, by a random one
    held for `repeat` steps; and whether the episode terminated (the task done) rather than ran out of time."""
    rng = np.random.default_rng(seed)
    env.action_space.seed(seed)
    held, left = None, 0

    def act(obs):
        nonlocal held, left
        action = expert.act(obs)
        if left == 0 and rng.random() < noise:
            held, left = env.action_space.sample(), repeat
        if left:
            action, left = held, left - 1
        return action

    traj, observations = rollout_trajectory(env, act, seed, {}, expert.reset)
    return observations.astype(np.float32), traj.meta["subtasks"] >= traj.meta["subtasks_total"]


class RankedRollouts:
    """Noisy rollouts of the scripted expert (or `actor`) padded to one length, their noise, r_psi's ranking loss."""

    def __init__(
        self,
        env,
        noise: list[float],
        episodes: int,
        *,
        seed: int = 50000,
        snippet: int = 50,
        repeat: int = 1,
        actor=None,
    ):
        expert = ScriptedExpert(env) if actor is None else actor  # actor: act(obs) and reset(), e.g. a cloned policy
        runs = [
            noisy_expert_rollout(env, expert, eps, seed + 1000 * i + k, repeat)
            for i, eps in enumerate(noise)
            for k in range(episodes)
        ]
        self.noise = np.repeat(np.asarray(noise, float), episodes)
        self.snippet = snippet
        horizon = max(len(obs) for obs, _ in runs)
        self.raw = np.stack([np.concatenate([obs, np.repeat(obs[-1:], horizon - len(obs), 0)]) for obs, _ in runs])
        self.absorbed = np.zeros(self.raw.shape[:2], bool)
        for j, (obs, ended) in enumerate(runs):
            self.absorbed[j, len(obs) :] = ended  # a rollout cut by the time limit is already the full length

    def states(self, normalize: Callable[[np.ndarray], np.ndarray]) -> torch.Tensor:
        """Augmented states (rollouts, steps, d + 1), normalised as the discriminator sees them now."""
        n, h, d = self.raw.shape
        s = augment(torch.as_tensor(normalize(self.raw.reshape(n * h, d)), dtype=torch.float32)).reshape(n, h, d + 1)
        flag = torch.as_tensor(self.absorbed)
        s[flag] = absorbing_states(int(flag.sum()), d)
        return s

    def loss(
        self, disc: Discriminator, states: torch.Tensor, rng: np.random.Generator, pairs: int = 32
    ) -> torch.Tensor:
        """Mean -log P(the less noisy snippet sums higher) over random pairs of rollouts of different noise."""
        i, j = rng.integers(0, len(self.noise), (2, pairs))
        keep = self.noise[i] != self.noise[j]
        i, j = i[keep], j[keep]
        if not len(i):
            return torch.zeros(())
        swap = self.noise[i] > self.noise[j]
        better, worse = np.where(swap, j, i), np.where(swap, i, j)
        steps = states.shape[1]
        start = rng.integers(0, max(steps - self.snippet, 1), len(better))
        t = np.minimum(start[:, None] + np.arange(self.snippet), steps - 1)
        margin = disc.reward(states[better[:, None], t]).sum(-1) - disc.reward(states[worse[:, None], t]).sum(-1)
        return torch.nn.functional.softplus(-margin).mean()
