"""Adversarial discriminators: GAIL, and AIRL with the shaped form f = r_psi(s) + gamma h(s') - h(s).

Inputs carry one extra column, the absorbing flag: an episode that terminates (the task is done) continues
in an absorbing state forever, so demonstrations and rollouts of different lengths are compared fairly
(Kostrikov et al., "Discriminator-Actor-Critic"). Truncated episodes are bootstrapped by the generator.
Each network's value at the absorbing state is a learned constant of its own, not the network evaluated at
a made-up input: a spectrally normalised network could not tell that input from ordinary states.
With `inputs`, the networks see only those observation columns (and the flag); the policy still sees all.
With `reward_inputs`, shaped AIRL's r_psi sees only those (h still sees `inputs`).
"""

from __future__ import annotations

from dataclasses import dataclass
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


def augment(obs: torch.Tensor) -> torch.Tensor:
    """Observations with a zero absorbing flag appended."""
    return torch.cat([obs, torch.zeros_like(obs[..., :1])], dim=-1)


def absorbing_states(k: int, obs_dim: int) -> torch.Tensor:
    """k absorbing states: zero observation, flag 1."""
    s = torch.zeros(k, obs_dim + 1)
    s[:, -1] = 1.0
    return s


@dataclass(frozen=True, kw_only=True)
class DiscriminatorForm:
    """How a discriminator is built: GAIL or AIRL, its networks, and which terms its logit has."""

    kind: Literal["gail", "airl"]
    gamma: float
    hidden: tuple[int, ...] = (64, 64)
    spectral: bool = False
    absorbing: bool = True
    shaped: bool = True  # AIRL's shaped form; else one network on (s, s')
    policy_term: bool = True


class Discriminator(nn.Module):
    """Logits of 'expert' for transitions (s, s', terminal, log pi(a|s)) of augmented states; state-only rewards."""

    def __init__(
        self,
        obs_dim: int,
        form: DiscriminatorForm,
        *,
        inputs: list[int] | None = None,
        reward_inputs: list[int] | None = None,
    ):
        super().__init__()
        self.obs_dim, self.kind, self.gamma, self.policy_term = obs_dim, form.kind, form.gamma, form.policy_term
        self.hidden, self.spectral, self.absorbing = tuple(form.hidden), form.spectral, form.absorbing
        self.shaped = form.kind == "airl" and form.shaped
        self.inputs = None if inputs is None else [int(i) for i in inputs]
        self.reward_inputs = self.inputs if reward_inputs is None else [int(i) for i in reward_inputs]
        for name, cols in (("_columns", self.inputs), ("_reward_columns", self.reward_inputs)):
            self.register_buffer(name, None if cols is None else torch.tensor([*cols, obs_dim]), persistent=False)
        width = (obs_dim if inputs is None else len(self.inputs)) + 1
        if self.shaped:
            reward_width = (obs_dim if self.reward_inputs is None else len(self.reward_inputs)) + 1
            self.r_psi = mlp(reward_width, self.hidden, sn=self.spectral)  # the reward kept for scoring
            self.h = mlp(width, self.hidden, sn=self.spectral)  # the shaping potential
            self.h_absorbing = nn.Parameter(torch.zeros(()))
        else:
            self.net = mlp(2 * width, self.hidden, sn=self.spectral)
        self.r_absorbing = nn.Parameter(torch.zeros(()))  # r_psi (or net) at the absorbing state

    @staticmethod
    def _masked(net_out: torch.Tensor, flag: torch.Tensor, constant: torch.Tensor) -> torch.Tensor:
        """The network's output on real states, the constant on absorbing ones."""
        return (1.0 - flag) * net_out.squeeze(-1) + flag * constant

    @staticmethod
    def _seen(s: torch.Tensor, columns: torch.Tensor | None) -> torch.Tensor:
        """These columns of augmented states (all if None)."""
        return s if columns is None else s.index_select(-1, columns)

    def _r(self, s):
        return self._masked(self.r_psi(self._seen(s, self._reward_columns)), s[..., -1], self.r_absorbing)

    def _h(self, s):
        return self._masked(self.h(self._seen(s, self._columns)), s[..., -1], self.h_absorbing)

    def _net(self, s, s2):
        pair = torch.cat([self._seen(s, self._columns), self._seen(s2, self._columns)], dim=-1)
        return self._masked(self.net(pair), s[..., -1], self.r_absorbing)

    def f(self, s, s2, terminal):
        """AIRL's f: shaped r_psi(s) + gamma h(s') - h(s) (terminal potential 0 without absorbing), or net(s, s')."""
        if not self.shaped:
            return self._net(s, s2)
        keep = 1.0 if self.absorbing else 1.0 - terminal
        return self._r(s) + self.gamma * keep * self._h(s2) - self._h(s)

    def logits(self, s, s2, terminal, log_pi):
        """log D - log(1 - D): AIRL's f - log pi (f alone without the policy term), or GAIL's network output."""
        if self.kind == "airl":
            return self.f(s, s2, terminal) - (log_pi if self.policy_term else 0.0)
        return self._net(s, s2)

    def generator_reward(self, s, s2, terminal, log_pi, entropy: bool = True):
        """What the generator maximises: AIRL log D - log(1 - D) (no -log pi unless `entropy`); GAIL -log(1 - D)."""
        z = self.logits(s, s2, terminal, log_pi if entropy else torch.zeros_like(log_pi))
        return z if self.kind == "airl" else nn.functional.softplus(z)

    def absorbing_value(self) -> float:
        """Discounted value of staying absorbed forever, r(abs, abs) / (1 - gamma); 0 without absorbing states."""
        if not self.absorbing:
            return 0.0
        s = absorbing_states(1, self.obs_dim)
        with torch.no_grad():
            r = float(self.generator_reward(s, s, torch.zeros(1), torch.zeros(1))[0])
        return r / max(1.0 - self.gamma, 1e-3)

    def terminal_bonus(self, terminal: torch.Tensor) -> torch.Tensor:
        """What a terminated transition adds to the generator's reward: gamma V(absorbing)."""
        return terminal * self.gamma * self.absorbing_value()

    def reward(self, s):
        """The learned state reward r_psi(s) (shaped AIRL only) of augmented states, separate from the shaping."""
        if not self.shaped:
            raise ValueError("only shaped AIRL has a separable state reward r_psi")
        return self._r(s)

    def potential(self, s):
        """AIRL's shaping potential h(s) of augmented states."""
        if not self.shaped:
            raise ValueError("only shaped AIRL has a shaping potential h")
        return self._h(s)

    def config(self) -> dict:
        """What rebuilds this discriminator (for pickle-free saving)."""
        return {
            "obs_dim": self.obs_dim,
            "kind": self.kind,
            "gamma": self.gamma,
            "hidden": list(self.hidden),
            "spectral": self.spectral,
            "absorbing": self.absorbing,
            "shaped": self.shaped,
            "policy_term": self.policy_term,
            "inputs": self.inputs,
            "reward_inputs": self.reward_inputs,
        }
