"""Shaped AIRL's reward averaged over training: r_psi and h copied every so many steps, exported as their mean.

Adversarial IRL is a two-player game, and what no-regret play converges to is the average of its iterates; the
last discriminator mostly reflects the latest rollouts. Each copy keeps the observation normalisation it saw.
"""

from __future__ import annotations

import torch
from stable_baselines3.common.callbacks import BaseCallback

from .discriminator import Discriminator
from .export import reward_snapshot


class RewardAveraging(BaseCallback):
    """At the first rollout end past every `every` environment steps, keep a snapshot of r_psi and h.

    Checkpoints save the snapshots (state_dict), so a resumed run averages the same ones."""

    def __init__(self, disc: Discriminator, every: int):
        super().__init__()
        if not disc.shaped:
            raise ValueError("reward averaging is for shaped AIRL (r_psi and h)")
        self.disc, self.every = disc, every
        self.snapshots: list[dict[str, torch.Tensor]] = []
        self.next_at = every

    def _on_training_start(self) -> None:
        self.next_at = (self.model.num_timesteps // self.every + 1) * self.every

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        if self.model.num_timesteps >= self.next_at:
            self.snapshots.append(reward_snapshot(self.disc, self.model.get_env()))
            self.next_at = (self.model.num_timesteps // self.every + 1) * self.every

    def state_dict(self) -> dict[str, torch.Tensor]:
        """The snapshots as one flat dict ('<k>.<tensor>')."""
        return {f"{k}.{name}": t for k, snap in enumerate(self.snapshots) for name, t in snap.items()}

    def load_state_dict(self, state: dict[str, torch.Tensor]) -> None:
        """Restore what state_dict gave (an empty dict: no snapshots yet)."""
        snaps: dict[int, dict[str, torch.Tensor]] = {}
        for key, t in state.items():
            k, name = key.split(".", 1)
            snaps.setdefault(int(k), {})[name] = t
        self.snapshots = [snaps[k] for k in sorted(snaps)]
