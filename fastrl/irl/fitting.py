"""Discriminator batches (with absorbing transitions) and the binary cross-entropy fit: expert 1, policy 0."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from ..agents.eager_adam import EagerAdam
from .discriminator import Discriminator, absorbing_states, augment


@dataclass
class Transitions:
    """Transitions (raw observations) with the actions that produced them."""

    obs: np.ndarray
    next_obs: np.ndarray
    terminal: np.ndarray
    actions: np.ndarray

    def __len__(self) -> int:
        return len(self.obs)

    def take(self, rows) -> Transitions:
        """The rows `rows`."""
        return Transitions(self.obs[rows], self.next_obs[rows], self.terminal[rows], self.actions[rows])


@dataclass
class Batch:
    """Discriminator inputs: augmented states s, s', terminal flags and log pi(a|s)."""

    s: torch.Tensor
    s2: torch.Tensor
    terminal: torch.Tensor
    log_pi: torch.Tensor

    def __len__(self) -> int:
        return len(self.s)

    def take(self, idx) -> Batch:
        """The rows idx."""
        return Batch(self.s[idx], self.s2[idx], self.terminal[idx], self.log_pi[idx])

    def cat(self, other: Batch) -> Batch:
        """This batch's rows followed by other's."""
        return Batch(
            *(
                torch.cat([a, b])
                for a, b in (
                    (self.s, other.s),
                    (self.s2, other.s2),
                    (self.terminal, other.terminal),
                    (self.log_pi, other.log_pi),
                )
            )
        )


def make_batch(obs, next_obs, terminal, log_pi, absorbing: bool) -> Batch:
    """Tensors of (normalised) observations, plus one absorbing transition per terminated one."""
    s, s2 = augment(torch.as_tensor(obs, dtype=torch.float32)), augment(torch.as_tensor(next_obs, dtype=torch.float32))
    term = torch.as_tensor(terminal, dtype=torch.float32).reshape(-1)
    log_pi = torch.as_tensor(log_pi, dtype=torch.float32).reshape(-1)
    k = int(term.sum()) if absorbing else 0
    if k:
        a = absorbing_states(k, s.shape[1] - 1)
        s, s2 = torch.cat([s, a]), torch.cat([s2, a])
        term, log_pi = torch.cat([term, torch.zeros(k)]), torch.cat([log_pi, torch.zeros(k)])
    return Batch(s, s2, term, log_pi)


def input_gradient_norm(disc: Discriminator, policy: Batch, expert: Batch, alpha: torch.Tensor) -> torch.Tensor:
    """Norm of the logit's gradient with respect to (s, s') at points between paired policy and expert rows."""
    mix = lambda a, b: alpha * b + (1.0 - alpha) * a  # noqa: E731
    s = mix(policy.s, expert.s).requires_grad_(True)
    s2 = mix(policy.s2, expert.s2).requires_grad_(True)
    z = disc.logits(
        s, s2, mix(policy.terminal[:, None], expert.terminal[:, None])[:, 0], torch.zeros_like(policy.log_pi)
    )
    gs, gs2 = torch.autograd.grad(z.sum(), [s, s2], create_graph=True)
    return torch.sqrt((gs**2).sum(-1) + (gs2**2).sum(-1) + 1e-12)


class DiscriminatorFit:
    """Adam on binary cross-entropy, minibatches of policy rows each paired with as many expert rows.

    With `gradient_penalty` > 0, each step adds that weight times (|grad_(s, s') logit| - 1)^2 at random points
    between the paired rows (the WGAN-GP penalty, as in Discriminator-Actor-Critic)."""

    def __init__(
        self,
        disc: Discriminator,
        *,
        lr: float = 3e-4,
        batch_size: int = 256,
        seed: int = 0,
        gradient_penalty: float = 0.0,
    ):
        self.disc, self.batch_size, self.gradient_penalty = disc, batch_size, gradient_penalty
        self.ranking: Callable[[], torch.Tensor] | None = None  # a weighted ranking loss added to each step
        self.optim = EagerAdam(disc.parameters(), lr=lr)
        self.rng = np.random.default_rng(seed)

    def epochs(self, policy: Batch, expert: Batch, epochs: int) -> dict[str, float]:
        """Passes over the policy rows; return mean loss, accuracy, and logits on both sides."""
        n_batches = max(1, len(policy) // self.batch_size)
        batches = [idx for _ in range(epochs) for idx in np.array_split(self.rng.permutation(len(policy)), n_batches)]
        return self._fit(policy, expert, batches)

    def steps(self, policy: Batch, expert: Batch, steps: int) -> dict[str, float]:
        """Gradient steps on minibatches drawn with replacement from the policy rows."""
        size = min(self.batch_size, len(policy))
        return self._fit(policy, expert, [self.rng.integers(0, len(policy), size) for _ in range(steps)])

    def _fit(self, policy: Batch, expert: Batch, batches: list[np.ndarray]) -> dict[str, float]:
        bce = torch.nn.functional.binary_cross_entropy_with_logits
        losses, accs, z_p, z_e, ranks = [], [], [], [], []
        for idx in batches:
            p, e = policy.take(idx), expert.take(self.rng.integers(0, len(expert), len(idx)))
            zp = self.disc.logits(p.s, p.s2, p.terminal, p.log_pi)
            ze = self.disc.logits(e.s, e.s2, e.terminal, e.log_pi)
            loss = bce(zp, torch.zeros_like(zp)) + bce(ze, torch.ones_like(ze))
            penalty = 0.0
            if self.gradient_penalty:
                alpha = torch.as_tensor(self.rng.random((len(idx), 1)), dtype=torch.float32)
                penalty = self.gradient_penalty * ((input_gradient_norm(self.disc, p, e, alpha) - 1.0) ** 2).mean()
            rank = torch.zeros(()) if self.ranking is None else self.ranking()
            self.optim.zero_grad()
            (loss + penalty + rank).backward()
            self.optim.step()
            losses.append(float(loss.detach()))  # the cross-entropy alone, comparable with and without the penalty
            accs.append(0.5 * float((zp < 0).float().mean() + (ze > 0).float().mean()))
            z_p.append(float(zp.detach().mean()))
            z_e.append(float(ze.detach().mean()))
            ranks.append(float(rank.detach()))
        stats = {
            "irl/disc_loss": float(np.mean(losses)),
            "irl/disc_accuracy": float(np.mean(accs)),
            "irl/logit_policy": float(np.mean(z_p)),
            "irl/logit_expert": float(np.mean(z_e)),
        }
        if self.ranking is not None:
            stats["irl/ranking_loss"] = float(np.mean(ranks))
        return stats

    def reward_stats(self, policy: Batch, expert: Batch) -> dict[str, float]:
        """Mean learned reward (r_psi for shaped AIRL, else the logit) on policy and expert rows."""
        with torch.no_grad():
            if self.disc.shaped:
                rp, re = self.disc.reward(policy.s), self.disc.reward(expert.s)
            else:
                rp = self.disc.logits(policy.s, policy.s2, policy.terminal, policy.log_pi)
                re = self.disc.logits(expert.s, expert.s2, expert.terminal, expert.log_pi)
        return {
            "irl/reward_policy": float(rp.mean()),
            "irl/reward_expert": float(re.mean()),
            "irl/absorbing_value": self.disc.absorbing_value(),
        }

    def state_dict(self) -> dict:
        """Discriminator and optimizer tensors, for checkpoints."""
        return {"disc": self.disc.state_dict(), "optim": self.optim.state_dict()}

    def load_state_dict(self, state: dict) -> None:
        """Restore what state_dict gave."""
        self.disc.load_state_dict(state["disc"])
        self.optim.load_state_dict(state["optim"])
