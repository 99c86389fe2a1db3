"""PPO's actor-critic whose critic sees only some observation columns, the actor all of them."""

from __future__ import annotations

import torch
from stable_baselines3.common.torch_layers import MlpExtractor
from torch import nn

from .lean_policy import LeanActorCriticPolicy


class ColumnSelect(nn.Linear):
    """A fixed 0/1 linear map keeping some input columns (a plain linear layer to export and evaluate)."""

    def __init__(self, width: int, columns: list[int]):
        super().__init__(width, len(columns), bias=False)
        self.columns = [int(c) for c in columns]
        self.weight.requires_grad_(False)
        self.select()

    def select(self) -> None:
        """Set the weights to the selection (again after an initialisation overwrote them)."""
        with torch.no_grad():
            self.weight.zero_()
            self.weight[torch.arange(len(self.columns)), torch.tensor(self.columns)] = 1.0


class ColumnCriticPolicy(LeanActorCriticPolicy):
    """LeanActorCriticPolicy whose value MLP reads `critic_columns` of the (normalised, flat) observation."""

    def __init__(self, *args, critic_columns: list[int], **kwargs):
        self.critic_columns = list(critic_columns)
        super().__init__(*args, **kwargs)

    def _build_mlp_extractor(self) -> None:
        super()._build_mlp_extractor()
        vf = self.net_arch["vf"] if isinstance(self.net_arch, dict) else self.net_arch
        narrow = MlpExtractor(len(self.critic_columns), {"pi": [], "vf": vf}, self.activation_fn, self.device)
        select = ColumnSelect(self.features_dim, self.critic_columns)
        self.mlp_extractor.value_net = nn.Sequential(select, narrow.value_net).to(self.device)

    def _build(self, lr_schedule) -> None:
        super()._build(lr_schedule)
        self.mlp_extractor.value_net[0].select()  # the orthogonal initialisation wrote over it
