"""A ranking prior for shaped AIRL's r_psi from automatically ranked demonstrations (D-REX, Brown et al. 2019).

The scripted expert is rolled out with its actions replaced by random ones at several rates (each held for a few
steps if asked, so that the scope also wanders into the walls): more noise, worse behaviour. Each discriminator
step then asks r_psi to sum higher over a snippet of a less noisy rollout than over the same time steps of a
noisier one (Bradley-Terry), so the reward also orders behaviour far from the expert's.
A rollout that ended (the task done) continues in the absorbing state up to the time limit.
The support loss asks r_psi to rate each demonstrated state above a noisy copy of it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from ..agents.expert import ScriptedExpert
from ..data.overlays import overlaid
from ..data.replay import replay_arrays, rollout_trajectory
from ..data.trajectory import Trajectory
from ..spec.irl import DiscriminatorSettings
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


def noisy_rollouts_batched(
    envs: list, act_batch: Callable[[np.ndarray], np.ndarray], noise: list[float], seeds: list[int], repeat: int = 1
) -> list[tuple[np.ndarray, bool]]:
    """noisy_expert_rollout of a deterministic batch policy for each (noise, seed) pair, one env each (`envs` at
    least as many), stepped in lockstep with one policy call per step: the same rollouts, not one call per step each."""
    n = len(seeds)
    rngs = [np.random.default_rng(seed) for seed in seeds]
    held, left = [None] * n, [0] * n
    obs, traces, ended = [], [], [False] * n
    for env, seed in zip(envs, seeds):
        env.action_space.seed(seed)
        obs.append(env.reset(seed=seed)[0])
        traces.append([obs[-1]])
    live = list(range(n))
    while live:
        actions = act_batch(np.stack([obs[i] for i in live]))
        still = []
        for i, action in zip(live, actions):
            if left[i] == 0 and rngs[i].random() < noise[i]:
                held[i], left[i] = envs[i].action_space.sample(), repeat
            if left[i]:
                action, left[i] = held[i], left[i] - 1
            obs[i], _, term, trunc, info = envs[i].step(action)
            traces[i].append(obs[i])
            if term or trunc:
                ended[i] = info["subtask"] >= info["subtasks_total"]
            else:
                still.append(i)
        live = still
    return [(np.array(t).astype(np.float32), e) for t, e in zip(traces, ended)]


def degraded_recording(
    env, traj: Trajectory, eps: float, seed: int, overlays: tuple[str, ...]
) -> tuple[np.ndarray, bool]:
    """Raw observations of a recording with each of the kinematic `overlays` at severity `eps` (0: as recorded),
    replayed; and whether it still completed the task."""
    u = env.unwrapped
    hz = u.task_spec.episode.control_hz
    portal = overlaid(traj.portal, dict.fromkeys(overlays, eps), seed, hz, u.task.ranges)
    copy = Trajectory(traj.time[0] + np.arange(len(portal)) / hz, portal, traj.meta)
    done = replay_arrays(env, copy)
    return done.observations.astype(np.float32), done.success


class RankedRollouts:
    """Noisy rollouts of the scripted expert (or `actor`), and degraded copies of `recordings`, as the ranking
    `settings` ask, padded to one length; their noise, and r_psi's ranking loss over pairs of the same source. With
    `envs` (one per rollout) an actor with `act_batch(observations)` rolls out in lockstep."""

    def __init__(
        self,
        env,
        settings: DiscriminatorSettings,
        *,
        seed: int = 50000,
        snippet: int = 50,
        actor=None,
        recordings: list[Trajectory] = (),
        envs: list = (),
    ):
        noise, episodes, repeat = settings.ranking_noise, settings.ranking_episodes, settings.ranking_repeat
        degrade = settings.degraded_overlays
        expert = ScriptedExpert(env) if actor is None else actor  # actor: act(obs) and reset(), e.g. a cloned policy
        jobs = [(eps, seed + 1000 * i + k) for i, eps in enumerate(noise) for k in range(episodes)]
        if envs and hasattr(expert, "act_batch"):  # a stateless policy: all rollouts in lockstep
            runs = noisy_rollouts_batched(envs, expert.act_batch, *map(list, zip(*jobs)), repeat)
        else:
            runs = [noisy_expert_rollout(env, expert, eps, s, repeat) for eps, s in jobs]
        self.noise = np.repeat(np.asarray(noise, float), episodes)
        self.source = np.zeros(len(runs), int)
        usable = [r for r in recordings if r.portal is not None and r.instruments is None] if degrade else []
        copies = [(eps, r) for eps in noise for r in usable]
        runs += [degraded_recording(env, r, eps, seed + k, degrade) for k, (eps, r) in enumerate(copies)]
        self.noise = np.concatenate([self.noise, [eps for eps, _ in copies]])
        self.source = np.concatenate([self.source, np.ones(len(copies), int)])
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

    def pairs(self, rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Up to n random (less noisy, noisier) pairs of rollouts of the same source."""
        i, j = rng.integers(0, len(self.noise), (2, n))
        keep = (self.noise[i] != self.noise[j]) & (self.source[i] == self.source[j])
        i, j = i[keep], j[keep]
        swap = self.noise[i] > self.noise[j]
        return np.where(swap, j, i), np.where(swap, i, j)

    def loss(
        self, disc: Discriminator, states: torch.Tensor, rng: np.random.Generator, pairs: int = 32
    ) -> torch.Tensor:
        """Mean -log P(the less noisy snippet sums higher) over random pairs of rollouts of different noise."""
        better, worse = self.pairs(rng, pairs)
        if not len(better):
            return torch.zeros(())
        steps = states.shape[1]
        start = rng.integers(0, max(steps - self.snippet, 1), len(better))
        t = np.minimum(start[:, None] + np.arange(self.snippet), steps - 1)
        margin = disc.reward(states[better[:, None], t]).sum(-1) - disc.reward(states[worse[:, None], t]).sum(-1)
        return torch.nn.functional.softplus(-margin).mean()


def support_loss(
    disc: Discriminator, shown: torch.Tensor, rng: np.random.Generator, spread: float, rows: int = 256
) -> torch.Tensor:
    """Mean -log P(r_psi rates a demonstrated state above a copy with Gaussian noise of `spread` on its normalised
    observation) over `rows` random states of `shown` (augmented, none absorbing): what the demonstrations never
    do ranks below what they do nearby. Zero, drawing nothing, where `spread` is 0."""
    if not spread or not len(shown):
        return torch.zeros(())
    s = shown[torch.as_tensor(rng.integers(0, len(shown), rows))]
    noise = torch.as_tensor(rng.standard_normal(s.shape) * spread, dtype=s.dtype)
    noise[:, -1] = 0.0  # the absorbing flag stays
    return torch.nn.functional.softplus(disc.reward(s + noise) - disc.reward(s)).mean()
