"""Pickle-free export of a run's networks: policy, value and learned reward (with its potential) as safetensors.

Each network is one NAME.safetensors file: a flat dict of tensors, with a JSON description in its header metadata
under "fastrl" (the layer lists, the observation normalisation, how the parts combine). Loading needs only
safetensors and numpy (fastrl.irl.networks), or torch (docs/networks.md); no stable-baselines3.
"""

from __future__ import annotations

import json
from contextlib import contextmanager
from pathlib import Path

import torch
from gymnasium import spaces
from safetensors.torch import save as save_safetensors
from stable_baselines3 import SAC
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.running_mean_std import RunningMeanStd
from stable_baselines3.common.torch_layers import FlattenExtractor
from stable_baselines3.common.vec_env import VecEnv, unwrap_vec_normalize
from torch import nn

from ..atomic import atomic_write
from .discriminator import Discriminator
from .fitting import Transitions
from .network_parts import FORMAT, HEADER_KEY
from .networks import Networks, load_networks

ACTIVATIONS = {nn.Tanh: "tanh", nn.ReLU: "relu"}

# ----------------------------------------------------------------------------------------------- export


@contextmanager
def _eval_mode(module: nn.Module):
    """Eval mode (spectral norm without a power-iteration step) and no grad, restoring each submodule's mode."""
    modes = [(m, m.training) for m in module.modules()]
    module.eval()
    try:
        with torch.no_grad():
            yield
    finally:
        for m, training in modes:
            m.training = training


def _tensor(x) -> torch.Tensor:
    """A detached, compact CPU copy (torch.save of a view would store the whole storage)."""
    return torch.as_tensor(x).detach().cpu().clone().contiguous()


def mlp_layers(module: nn.Module) -> list[dict]:
    """A feed-forward module as layers: linear (effective weight, bias) or an activation; nested Sequentials flatten."""
    if isinstance(module, nn.Sequential):
        return [layer for child in module for layer in mlp_layers(child)]
    if isinstance(module, nn.Linear):  # spectral-normed layers too: .weight evaluates the parametrization
        bias = None if module.bias is None else _tensor(module.bias)
        return [{"type": "linear", "weight": _tensor(module.weight), "bias": bias}]
    if isinstance(module, nn.Identity):
        return []
    if isinstance(module, nn.Hardtanh):  # SAC with gSDE clips its mean so
        return [{"type": "hardtanh", "min": float(module.min_val), "max": float(module.max_val)}]
    if type(module) in ACTIVATIONS:
        return [{"type": ACTIVATIONS[type(module)]}]
    raise ValueError(
        f"cannot export module {type(module).__name__}: only Sequential, Linear, Tanh, ReLU, "
        "Hardtanh and Identity are supported"
    )


def export_parts(parts: dict[str, nn.Module]) -> tuple[dict, dict[str, torch.Tensor]]:
    """Named MLP parts as (JSON layer lists, flat tensors '<part>.<i>.weight'/'bias')."""
    specs, tensors = {}, {}
    for name, module in parts.items():
        with _eval_mode(module):
            layers = mlp_layers(module)
        specs[name] = []
        for i, layer in enumerate(layers):
            if layer["type"] != "linear":
                specs[name].append(layer)
                continue
            out_features, in_features = layer["weight"].shape
            specs[name].append(
                {"type": "linear", "in": in_features, "out": out_features, "bias": layer["bias"] is not None}
            )
            tensors[f"{name}.{i}.weight"] = layer["weight"]
            if layer["bias"] is not None:
                tensors[f"{name}.{i}.bias"] = layer["bias"]
    return specs, tensors


def obs_normalization(venv: VecEnv | None) -> tuple[dict | None, dict[str, torch.Tensor]]:
    """The venv's VecNormalize observation statistics as (JSON constants, tensors); (None, {}) for identity."""
    norm = unwrap_vec_normalize(venv) if venv is not None else None
    if norm is None or not norm.norm_obs:
        return None, {}
    if not isinstance(norm.obs_rms, RunningMeanStd):
        raise ValueError("cannot export the normalisation of dict observations")
    consts = {"clip": float(norm.clip_obs), "epsilon": float(norm.epsilon)}
    stats = {"obs_norm.mean": norm.obs_rms.mean, "obs_norm.var": norm.obs_rms.var}
    return consts, {k: _tensor(v).double() for k, v in stats.items()}


def _check_flat(model: BaseAlgorithm, *extractors: nn.Module) -> None:
    """Only flat Box observations through FlattenExtractors are exportable as plain MLPs."""
    space = model.observation_space
    if not (isinstance(space, spaces.Box) and len(space.shape) == 1):
        raise ValueError(f"cannot export a policy on observation space {space}: a 1-D Box is required")
    if not all(isinstance(e, FlattenExtractor) for e in extractors):
        raise ValueError("cannot export a custom features extractor: only FlattenExtractor is supported")


def _bounds(space: spaces.Box) -> dict[str, torch.Tensor]:
    """The action bounds as tensors (JSON has no infinities)."""
    return {"action.low": _tensor(space.low).double(), "action.high": _tensor(space.high).double()}


def policy_export(model: BaseAlgorithm) -> tuple[dict, dict[str, torch.Tensor]]:
    """The deterministic policy: the MLP 'pi' and the output rule (argmax, clip or tanh then rescale)."""
    space = model.action_space
    if isinstance(model, SAC):
        actor = model.actor
        _check_flat(model, actor.features_extractor)
        specs, tensors = export_parts({"pi": nn.Sequential(actor.latent_pi, actor.mu)})
        return {"parts": specs, "output": "tanh_rescale"}, {**tensors, **_bounds(space)}
    if not isinstance(model.policy, ActorCriticPolicy):
        raise ValueError(f"cannot export {type(model).__name__}: only PPO-style actor-critics and SAC are supported")
    policy = model.policy
    _check_flat(model, policy.pi_features_extractor)
    if policy.squash_output:
        raise ValueError("cannot export a squashed (gSDE) actor-critic policy")
    specs, tensors = export_parts({"pi": nn.Sequential(policy.mlp_extractor.policy_net, policy.action_net)})
    if isinstance(space, spaces.Discrete):
        return {"parts": specs, "output": "argmax"}, tensors
    if isinstance(space, spaces.Box):
        return {"parts": specs, "output": "clip"}, {**tensors, **_bounds(space)}
    raise ValueError(f"cannot export a policy for action space {space}: Discrete or Box is required")


def value_export(model: BaseAlgorithm) -> tuple[dict, dict[str, torch.Tensor]]:
    """The state value: PPO's value MLP 'v', or SAC's Q1(s, a*) with a* = tanh(pi(s)) ('pi', 'q1')."""
    if isinstance(model, SAC):
        actor, critic = model.actor, model.critic
        _check_flat(model, actor.features_extractor, critic.features_extractor)
        specs, tensors = export_parts({"pi": nn.Sequential(actor.latent_pi, actor.mu), "q1": critic.q_networks[0]})
        return {"parts": specs, "form": "q_of_policy"}, tensors
    if not isinstance(model.policy, ActorCriticPolicy):
        raise ValueError(f"cannot export {type(model).__name__}: only PPO-style actor-critics and SAC are supported")
    policy = model.policy
    _check_flat(model, policy.vf_features_extractor)
    specs, tensors = export_parts({"v": nn.Sequential(policy.mlp_extractor.value_net, policy.value_net)})
    return {"parts": specs, "form": "state"}, tensors


def reward_export(disc: Discriminator, gamma: float) -> tuple[dict, dict[str, torch.Tensor]]:
    """The learned reward: AIRL's r_psi and potential h, or GAIL's net on (s, s'); with the absorbing value."""
    shaped = disc.shaped
    parts = {"r_psi": disc.r_psi, "h": disc.h} if shaped else {"net": disc.net}
    specs, tensors = export_parts(parts)
    with _eval_mode(disc):
        absorbing_value = float(disc.absorbing_value())
    meta = {
        "parts": specs,
        "kind": disc.kind,
        "form": "state" if shaped else "transition",
        "gamma": float(gamma),
        "absorbing": bool(disc.absorbing),
        "absorbing_value": absorbing_value,
        "absorbing_reward": float(disc.r_absorbing.detach()),
        "inputs": disc.inputs,
        "reward_inputs": disc.reward_inputs if shaped else disc.inputs,
        "discriminator": disc.config(),
    }
    return meta, tensors


def reward_snapshot(disc: Discriminator, venv: VecEnv | None) -> dict[str, torch.Tensor]:
    """Shaped AIRL's r_psi and h as exported tensors, its absorbing reward, and the observation statistics now."""
    _, tensors = export_parts({"r_psi": disc.r_psi, "h": disc.h})
    tensors["r_absorbing"] = _tensor(disc.r_absorbing)
    _, norm = obs_normalization(venv)
    return tensors | norm


def same_tensors(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> bool:
    """Whether two flat dicts hold equal tensors under the same names."""
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


def average_export(snapshots: list[dict[str, torch.Tensor]]) -> tuple[dict, dict[str, torch.Tensor]]:
    """Snapshots of r_psi and h (the last one the final networks) as the members of an averaged reward."""
    tensors = {f"average.{k}.{name}": t for k, snap in enumerate(snapshots) for name, t in snap.items()}
    return {"average": {"members": len(snapshots)}}, tensors


def write_network(out_dir: Path, name: str, meta: dict, tensors: dict[str, torch.Tensor]) -> list[Path]:
    """NAME.safetensors: the tensors, with the description (format, network name, meta) as JSON in its header."""
    path = out_dir / f"{name}.safetensors"
    meta = {"format": FORMAT, "network": name, **meta}
    own = {k: t.detach().cpu().contiguous().clone() for k, t in tensors.items()}  # safetensors refuses shared storage
    data = save_safetensors(own, metadata={HEADER_KEY: json.dumps(meta)})
    atomic_write(path, lambda f: f.write(data), needed=len(data))
    return [path]


def save_networks(
    out_dir: Path,
    model: BaseAlgorithm,
    venv: VecEnv | None,
    disc: Discriminator | None,
    gamma: float,
    snapshots: list[dict[str, torch.Tensor]] | None = None,
    demonstrations: Transitions | None = None,
) -> list[Path]:
    """Write policy, value and (with a discriminator) reward as .safetensors files into out_dir; return the paths.

    With `snapshots` (shaped AIRL's r_psi and h during training), the reward also holds them and the final
    networks as the members of their average. With `demonstrations`, value and reward also hold their `ceiling`
    (demonstrated_ceilings)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    norm, norm_tensors = obs_normalization(venv)
    exports = {"policy": policy_export(model), "value": value_export(model)}
    if disc is not None:
        meta, tensors = reward_export(disc, gamma)
        if snapshots is not None and disc.shaped:
            final = reward_snapshot(disc, venv)
            earlier = [snap for snap in snapshots if not same_tensors(snap, final)]  # taken at the very end
            average_meta, average_tensors = average_export([*earlier, final])
            meta, tensors = meta | average_meta, tensors | average_tensors
        exports["reward"] = meta, tensors
    else:  # a stale reward from an earlier export would be loaded as this run's
        (out_dir / "reward.safetensors").unlink(missing_ok=True)
    common = {"obs_dim": int(model.observation_space.shape[0]), "obs_norm": norm}
    paths = []
    for name, (meta, tensors) in exports.items():
        paths += write_network(out_dir, name, meta | common, tensors | norm_tensors)
    if "reward" in exports and demonstrations is not None and len(demonstrations):
        for name, ceiling in demonstrated_ceilings(load_networks(out_dir), demonstrations).items():
            meta, tensors = exports[name]
            write_network(out_dir, name, meta | common | {"ceiling": ceiling}, tensors | norm_tensors)
    return paths


def demonstrated_ceilings(networks: Networks, shown: Transitions) -> dict[str, float]:
    """The highest learned value of any demonstrated state and reward of any demonstrated transition, as loading
    evaluates them: the zero each learned score counts from."""
    return {
        "value": float(networks.value(shown.obs).max()),
        "reward": float(networks.transition_reward(shown.obs, shown.next_obs).max()),
    }


# ----------------------------------------------------------------------------------------------- load
