"""Load exported networks (NAME.safetensors) and evaluate them with numpy: scoring, cues and the viewer never import
torch (its import alone costs seconds); training keeps torch and SB3, and the tests check the two agree."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .network_files import has_networks as has_networks  # re-exported: its old home
from .network_parts import Loaded, Mlp, ObsNorm, build_mlp, build_norm, read_pair


@dataclass(frozen=True)
class RewardMember:
    """One member of an averaged shaped-AIRL reward: r_psi, h, the absorbing reward and the normalisation they saw."""

    r_psi: Mlp
    h: Mlp
    r_absorbing: float
    norm: ObsNorm


def checked_ceiling(loaded: Loaded) -> Loaded:
    """The loaded pair, if its optional `ceiling` (the best demonstrated output) is a finite number."""
    ceiling = loaded.meta.get("ceiling", 0.0)
    if type(ceiling) not in (int, float) or not np.isfinite(ceiling):
        raise ValueError(f"{loaded.path}: ceiling must be a finite number, got {ceiling!r}")
    return loaded


def reward_members(r: Loaded) -> list[RewardMember]:
    """The members of an averaged reward ('average' in the JSON), each checked against the final parts' shapes."""
    average = r.meta["average"]
    count = average.get("members") if isinstance(average, dict) else None
    if type(count) is not int or count < 1:
        raise ValueError(f"{r.path}: average.members must be a positive integer, got {count!r}")
    members = []
    for k in range(count):
        prefix = f"average.{k}."
        own = {name[len(prefix) :]: t for name, t in r.tensors.items() if name.startswith(prefix)}
        try:
            members.append(
                RewardMember(
                    build_mlp("r_psi", r.meta["parts"]["r_psi"], own),
                    build_mlp("h", r.meta["parts"]["h"], own),
                    float(np.asarray(own["r_absorbing"]).reshape(-1)[0]),
                    build_norm(r.meta, own),
                )
            )
        except KeyError as e:
            raise ValueError(f"{r.path}: tensor {prefix}{e.args[0]} missing from the averaged reward") from e
        except ValueError as e:
            raise ValueError(f"{r.path}: member {k} of the averaged reward: {e}") from e
    return members


class Networks:
    """An exported run evaluated with numpy: policy, value, and the learned reward (if saved).

    A shaped AIRL reward saved with snapshots from training is their average unless `averaged` is false (then the
    final r_psi and h alone)."""

    def __init__(self, directory: Path, averaged: bool = True):
        self.directory = Path(directory)
        self._policy = read_pair(self.directory, "policy")
        bounds = ("pi", "action.low", "action.high")
        self.output = self._policy.variant("output", {"argmax": ("pi",), "clip": bounds, "tanh_rescale": bounds})
        self._value = checked_ceiling(read_pair(self.directory, "value"))
        self.value_form = self._value.variant("form", {"state": ("v",), "q_of_policy": ("pi", "q1")})
        self._reward = self._read_reward()
        self._members = self._read_members(averaged)

    def _read_reward(self) -> Loaded | None:
        """The reward pair, None if none was saved."""
        if not (self.directory / "reward.safetensors").exists():
            return None
        loaded = checked_ceiling(read_pair(self.directory, "reward"))
        loaded.variant("kind", {"airl": (), "gail": ()})
        loaded.variant("form", {"state": ("r_psi", "h"), "transition": ("net",)})
        for key in ("gamma", "absorbing", "absorbing_value", "absorbing_reward"):
            if key not in loaded.meta:
                raise ValueError(f"{loaded.path}: missing key {key!r}")
        for key in ("inputs", "reward_inputs"):
            cols = loaded.meta.get(key)
            if cols is not None and not (isinstance(cols, list) and all(type(i) is int and i >= 0 for i in cols)):
                raise ValueError(f"{loaded.path}: {key} must be a list of observation columns, got {cols!r}")
        return loaded

    def _read_members(self, averaged: bool) -> list[RewardMember]:
        """The averaged reward's members; one, the final networks, if not averaged or none were saved."""
        r = self._reward
        if r is None or r.meta["form"] != "state":
            return []
        if averaged and "average" in r.meta:
            return reward_members(r)
        return [RewardMember(r.parts["r_psi"], r.parts["h"], float(r.meta["absorbing_reward"]), r.norm)]

    @property
    def reward_members(self) -> int:
        """How many r_psi (and h) the shaped reward averages: 1 for the final networks alone."""
        return len(self._members)

    def policy(self, obs: np.ndarray) -> np.ndarray:
        """Deterministic actions for a batch of raw observations."""
        p = self._policy
        out = p.parts["pi"](p.norm(obs))
        if self.output == "argmax":
            return out.argmax(axis=-1)
        low, high = p.tensors["action.low"], p.tensors["action.high"]
        if self.output == "clip":
            return np.clip(out.astype(np.float64), low, high).astype(np.float32)
        return (low + 0.5 * (np.tanh(out).astype(np.float64) + 1.0) * (high - low)).astype(np.float32)

    def value(self, obs: np.ndarray) -> np.ndarray:
        """The generator's state value V(s) for a batch of raw observations (SAC: Q1(s, a*))."""
        v = self._value
        x = v.norm(obs)
        if self.value_form == "state":
            return v.parts["v"](x)[:, 0]
        action = np.tanh(v.parts["pi"](x))
        return v.parts["q1"](np.concatenate([x, action], axis=-1))[:, 0]

    def _reward_pair(self) -> Loaded:
        """The reward pair, or a clear error if none was saved."""
        if self._reward is None:
            raise ValueError(f"{self.directory}: no reward network was saved (no reward.safetensors)")
        return self._reward

    @property
    def kind(self) -> str | None:
        """'airl', 'gail', or None without a reward network."""
        return None if self._reward is None else self._reward.meta["kind"]

    @property
    def has_potential(self) -> bool:
        """Whether a shaped AIRL reward (with its potential h) was saved."""
        return self._reward is not None and self._reward.meta["form"] == "state"

    @property
    def identity(self) -> str:
        """Checksums of the saved value and reward tensors: changes whenever the networks do."""
        reward = "" if self._reward is None else self._reward.meta["sha256"][:16]
        return f"{self._value.meta['sha256'][:16]}-{reward}"

    @property
    def gamma(self) -> float:
        """The discount saved with the reward."""
        return float(self._reward_pair().meta["gamma"])

    def _states(self, r: Loaded, obs: np.ndarray, key: str = "inputs", norm: ObsNorm | None = None) -> np.ndarray:
        """Normalised observations (by `norm`, else the pair's), the columns a network saw (`inputs`, or r_psi's
        `reward_inputs`; all if not saved), with a zero absorbing flag."""
        x = (r.norm if norm is None else norm)(obs)
        columns = r.meta.get(key, r.meta.get("inputs"))
        if columns is not None:
            x = x[:, columns]
        return np.concatenate([x, np.zeros_like(x[:, :1])], axis=-1)

    def reward(self, obs: np.ndarray) -> np.ndarray:
        """Per-step reward (T,) of raw observations (T+1, d): AIRL r_psi(s_t), GAIL logit(s_t, s_t+1)."""
        return self.transition_reward(obs[:-1], obs[1:])

    def transition_reward(self, obs: np.ndarray, next_obs: np.ndarray) -> np.ndarray:
        """The reward (n,) of n transitions (s, s') of raw observations: AIRL r_psi(s), GAIL logit(s, s')."""
        r = self._reward_pair()
        if r.meta["form"] == "state":
            rows = [m.r_psi(self._states(r, obs, "reward_inputs", m.norm))[:, 0] for m in self._members]
            return np.stack(rows).mean(0, dtype=np.float32)
        s, s2 = self._states(r, obs), self._states(r, next_obs)
        return r.parts["net"](np.concatenate([s, s2], axis=-1))[:, 0]

    @property
    def reward_ceiling(self) -> float:
        """The highest reward of any demonstrated transition (0 for networks saved without it): AIRL and GAIL leave
        the reward's constant free, so a score sums reward minus this and no demonstrated step earns above zero."""
        return float(self._reward_pair().meta.get("ceiling", 0.0))

    @property
    def value_ceiling(self) -> float | None:
        """The highest value of any demonstrated state (None for networks saved without it)."""
        return self._value.meta.get("ceiling")

    def potential(self, obs: np.ndarray) -> np.ndarray:
        """AIRL's shaping potential h(s) of a batch of raw observations."""
        r = self._reward_pair()
        if r.meta["form"] != "state":
            raise ValueError(f"{r.path}: only shaped AIRL has a shaping potential h")
        return np.stack([m.h(self._states(r, obs, norm=m.norm))[:, 0] for m in self._members]).mean(0, dtype=np.float32)

    def absorbing_reward(self) -> float:
        """The learned reward of the absorbing state (a learned constant), in the same form as reward()."""
        if self._members:
            return float(np.mean([m.r_absorbing for m in self._members]))
        return float(self._reward_pair().meta["absorbing_reward"])

    def learned_return(self, obs: np.ndarray, terminated: bool, gamma: float | None = None) -> float:
        """sum_t gamma^t r_t, plus, if the episode terminated, gamma^T r(absorbing) / (1 - gamma) for what follows."""
        meta = self._reward_pair().meta
        g = float(meta["gamma"]) if gamma is None else float(gamma)
        r = self.reward(obs).astype(np.float64)
        ret = float(np.sum(g ** np.arange(len(r)) * r))
        if terminated and meta["absorbing"]:
            ret += g ** len(r) * self.absorbing_reward() / max(1.0 - g, 1e-3)
        return ret


def load_networks(directory: Path, averaged: bool = True) -> Networks:
    """The networks save_networks wrote into directory (safetensors)."""
    return Networks(Path(directory), averaged)
