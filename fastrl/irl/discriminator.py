"""Adversarial discriminators: GAIL, and AIRL with the shaped form f = r_psi(s) + gamma h(s') - h(s)."""

from __future__ import annotations

from typing import Literal

import torch
from torch import nn
from torch.nn.utils.parametrizations import spectral_norm


def mlp(inp: int, hidden: tuple[int, ...], out: int = 1, sn: bool = False) -> nn.Sequential:
    """A ReLU MLP, every linear layer optionally spectrally normalised."""
    layers, last = [], inp
    for h in (*hidden, out):
        lin = nn.Linear(last, h)
        layers += [spectral_norm(lin, n_power_iterations=3) if sn else lin, nn.ReLU()]
        last = h
    return nn.Sequential(*layers[:-1])


class Discriminator(nn.Module):
    """Logits of 'expert' for transitions (s, s', done, log pi(a|s)); state-only rewards."""

    def __init__(self, obs_dim: int, kind: Literal["gail", "airl"], gamma: float, hidden=(64, 64),
                 spectral: bool = False):
        super().__init__()
        self.kind, self.gamma = kind, gamma
        if kind == "airl":
            self.r_psi = mlp(obs_dim, hidden, sn=spectral)   # the reward kept for scoring
            self.h = mlp(obs_dim, hidden, sn=spectral)       # the shaping potential
        else:
            self.net = mlp(2 * obs_dim, hidden, sn=spectral)

    def f(self, obs, next_obs, terminal):
        """AIRL's shaped term r_psi(s) + gamma (1 - terminal) h(s') - h(s); the terminal potential is 0."""
        r = self.r_psi(obs).squeeze(-1)
        return r + self.gamma * (1.0 - terminal) * self.h(next_obs).squeeze(-1) - self.h(obs).squeeze(-1)

    def logits(self, obs, next_obs, terminal, log_pi):
        """log D - log(1 - D): AIRL's f - log pi, or GAIL's network output."""
        if self.kind == "airl":
            return self.f(obs, next_obs, terminal) - log_pi
        return self.net(torch.cat([obs, next_obs], dim=-1)).squeeze(-1)

    def generator_reward(self, obs, next_obs, terminal, log_pi):
        """What the policy maximises: AIRL log D - log(1-D); GAIL -log(1 - D)."""
        z = self.logits(obs, next_obs, terminal, log_pi)
        return z if self.kind == "airl" else nn.functional.softplus(z)

    def reward(self, obs):
        """The learned state reward r_psi(s) (AIRL only), separate from the shaping."""
        if self.kind != "airl":
            raise ValueError("only AIRL has a separable reward r_psi")
        return self.r_psi(obs).squeeze(-1)
