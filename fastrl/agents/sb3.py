"""Forward RL on stable-baselines3: vectorised envs, PPO/SAC from the spec, pickle-free checkpoints."""

from __future__ import annotations

import json
import os
import shutil
from functools import partial
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.policies import BasePolicy
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

from ..atomic import DiskFull, atomic_write, fsync_dir, is_disk_full, write_json
from ..env.fast_env import FastEnv
from ..spec.columns import value_inputs
from ..spec.models import TaskSpec
from ..spec.training import Encoder
from .checkpoint_files import CheckpointDamaged, CheckpointMismatch, checkpoint_problem, file_sha256
from .critic_columns import ColumnCriticPolicy
from .eager_adam import EagerAdam
from .encoder import PixelEncoder
from .lean_policy import LeanActorCriticPolicy
from .lean_sac import LeanSAC
from .workers import FreshInfoVecEnv, SplitVecEnv

ALGOS = {"PPO": PPO, "SAC": SAC}
ACTIVATIONS = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}


def make_vec_env(
    spec: TaskSpec,
    n_envs: int,
    seed: int,
    workers: int = 1,
    late_starts: float = 0.0,
    later_subtasks: float = 0.0,
    *,
    recorded: tuple = (),
    recorded_starts: float = 0.0,
) -> VecEnv:
    """Vectorised FastEnvs, stepped in batches by `workers` processes (this one included), optionally normalised;
    `late_starts`: each env's episodes after its first start up to that share of the time limit late;
    `later_subtasks`: that share of them at a random later subtask; `recorded_starts`: that share at a random state
    of the `recorded` (seed, portal) recordings.

    Cheap envs step fastest in batches: one process per env (SB3's SubprocVecEnv) costs more in messages than
    it gains. The split never changes the trajectories. Learning from demonstrations, env rewards are replaced
    by the discriminator's, so they are not normalised.
    """
    processes = min(workers, n_envs, os.cpu_count() or 1)
    # a partial pickles: image workers start from a fresh process
    make = partial(
        FastEnv,
        spec,
        late_starts=late_starts,
        later_subtasks=later_subtasks,
        recorded=recorded,
        recorded_starts=recorded_starts,
    )
    if processes > 1:
        venv = SplitVecEnv(make_env=make, n_envs=n_envs, processes=processes, fork=spec.observation.image is None)
    else:
        venv = FreshInfoVecEnv([make for _ in range(n_envs)])
    venv.seed(seed)
    train = spec.learning()
    norm = train.normalize
    norm_reward = norm.reward and not spec.irl.enabled
    norm_obs = norm.obs and spec.observation.image is None  # frames are scaled by the policy; a Dict's state not
    if norm_obs or norm_reward:
        venv = VecNormalize(venv, norm_obs=norm_obs, norm_reward=norm_reward, gamma=train.params().gamma)
    return venv


def build_model(spec: TaskSpec, venv: VecEnv, seed: int | None = None, **extra) -> BaseAlgorithm:
    """The spec's algorithm with the hyperparameters it learns with (`spec.learning()`) on the vectorised env
    (`extra`: more SB3 arguments)."""
    train = spec.learning()
    params = {**train.sb3_params(), **{k: v for k, v in extra.items() if v is not None}}
    net, act = params.pop("net_arch"), ACTIVATIONS[params.pop("activation")]
    kind = train.kind
    arch = {"pi": net, kind.critic: net}
    algo = LeanSAC if params.pop("lean_update", False) else ALGOS[kind.name]
    torch.set_num_threads(1)
    # the checks of every distribution's arguments took 30% of each rollout's policy call (528 -> 370 us for 32
    # observations) and PPO's updates pay them too; they change no number, the policy's outputs are finite
    torch.distributions.Distribution.set_default_validate_args(False)
    policy = LeanActorCriticPolicy if kind.name == "PPO" else "MlpPolicy"
    policy_kwargs = {"net_arch": arch, "activation_fn": act}
    if kind.name == "PPO":  # SB3's Adam with its eps for PPO, without the compiler's import
        policy_kwargs |= {"optimizer_class": EagerAdam, "optimizer_kwargs": {"eps": 1e-5}}
    critic_columns = value_inputs(spec)
    if critic_columns is not None and kind.name == "PPO":
        policy, policy_kwargs["critic_columns"] = ColumnCriticPolicy, critic_columns
    image = spec.observation.image
    if image is not None:
        enc = train.encoder or Encoder()
        policy = "MultiInputPolicy" if image.state else "CnnPolicy"
        extractor = {"features": enc.features, "shift": enc.shift}
        policy_kwargs |= {"features_extractor_class": PixelEncoder, "features_extractor_kwargs": extractor}
        if enc.critic_cnn:
            policy_kwargs["share_features_extractor"] = False
    return algo(
        policy,
        venv,
        seed=train.seed if seed is None else seed,
        verbose=0,
        device="cpu",
        policy_kwargs=policy_kwargs,
        **params,
    )


def _optimizers(model: BaseAlgorithm) -> dict[str, torch.optim.Optimizer]:
    """Every optimizer the algorithm trains with, by name."""
    if isinstance(model, SAC):
        opts = {"actor": model.actor.optimizer, "critic": model.critic.optimizer}
        if model.ent_coef_optimizer is not None:
            opts["ent_coef"] = model.ent_coef_optimizer
        return opts
    return {"policy": model.policy.optimizer}


def save_checkpoint(path: Path, model: BaseAlgorithm, venv: VecEnv, state: dict, parts: dict | None = None) -> Path:
    """Write weights and optimizer states (torch tensors only), normalisation stats (npz) and state (JSON).

    `parts` are more objects with state_dict (a discriminator and its optimizer), saved in parts.pt. The files go
    into a hidden directory, fsynced, which is then renamed to `path`: a kill at any moment leaves no
    half-written checkpoint under that name, and state.json lists every file's sha256 so a damaged one is found.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    try:
        optimizers = {k: o.state_dict() for k, o in _optimizers(model).items()}
        tensors = {"policy": model.policy.state_dict(), "optimizers": optimizers}
        if isinstance(model, SAC) and model.log_ent_coef is not None:
            tensors["log_ent_coef"] = model.log_ent_coef.detach().clone()
        atomic_write(tmp / "weights.pt", lambda f: torch.save(tensors, f))
        if parts:
            saved = {name: part.state_dict() for name, part in parts.items()}
            atomic_write(tmp / "parts.pt", lambda f: torch.save(saved, f))
        if isinstance(venv, VecNormalize):
            stats = {"ret_mean": venv.ret_rms.mean, "ret_var": venv.ret_rms.var, "ret_count": venv.ret_rms.count}
            if venv.norm_obs:  # not for image observations (the policy scales the frames)
                stats |= {"obs_mean": venv.obs_rms.mean, "obs_var": venv.obs_rms.var, "obs_count": venv.obs_rms.count}
            atomic_write(tmp / "normalize.npz", lambda f: np.savez(f, **stats))
        files = {p.name: file_sha256(p) for p in sorted(tmp.iterdir())}
        write_json(tmp / "state.json", {**state, "timesteps": int(model.num_timesteps), "files": files})
        if path.exists():  # the same timesteps saved again (e.g. resumed with nothing left to train)
            old = path.with_name(f".{path.name}.old-{os.getpid()}")
            os.replace(path, old)
            os.replace(tmp, path)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, path)
    except BaseException as e:
        shutil.rmtree(tmp, ignore_errors=True)
        if is_disk_full(e) and not isinstance(e, DiskFull):
            raise DiskFull(path) from None
        raise
    fsync_dir(path.parent)
    return path


def load_checkpoint(path: Path, model: BaseAlgorithm, venv: VecEnv | None, parts: dict | None = None) -> dict:
    """Restore what save_checkpoint wrote into a freshly built model (and its VecNormalize, and parts)."""
    problem = checkpoint_problem(path)
    if problem:
        raise CheckpointDamaged(f"checkpoint {path}: {problem}")
    tensors = torch.load(path / "weights.pt", map_location="cpu", weights_only=True)
    if parts:
        saved = torch.load(path / "parts.pt", map_location="cpu", weights_only=True)
        for name, part in parts.items():
            try:
                part.load_state_dict(saved.get(name, {}))  # a part the run had not saved yet starts empty
            except (RuntimeError, KeyError) as e:  # shapes differ, or it was never saved: the spec changed
                raise CheckpointMismatch(
                    f"{path / 'parts.pt'}: the saved {name} does not fit what the run's "
                    f"spec builds now ({str(e).splitlines()[-1].strip()})"
                ) from e
    model.policy.load_state_dict(tensors["policy"])
    for name, opt in _optimizers(model).items():
        opt.load_state_dict(tensors["optimizers"][name])
    if "log_ent_coef" in tensors and isinstance(model, SAC):
        with torch.no_grad():
            model.log_ent_coef.copy_(tensors["log_ent_coef"])
    stats = path / "normalize.npz"
    if isinstance(venv, VecNormalize) and stats.exists():
        z = np.load(stats)
        if venv.norm_obs:
            venv.obs_rms.mean, venv.obs_rms.var = z["obs_mean"], z["obs_var"]
            venv.obs_rms.count = float(z["obs_count"])
        venv.ret_rms.mean, venv.ret_rms.var, venv.ret_rms.count = z["ret_mean"], z["ret_var"], float(z["ret_count"])
    state = json.loads((path / "state.json").read_text())
    model.num_timesteps = int(state["timesteps"])
    state.pop("files", None)
    return state


def policy_function(model: BaseAlgorithm, venv: VecEnv | None, sampling_seed: int | None = None):
    """obs -> action, applying the training's observation normalisation: the most likely action, or with
    `sampling_seed` one sampled from the policy (reproducibly)."""
    norm = venv if isinstance(venv, VecNormalize) and venv.norm_obs else None
    predict = predictor(model, sampling_seed)

    def act(obs):
        one = {k: v[None] for k, v in obs.items()} if isinstance(obs, dict) else obs[None]  # a Dict's image and state
        action = predict(norm.normalize_obs(one) if norm is not None else one)
        return action[0] if action.ndim > 1 else int(action[0])

    return act


def batch_policy(model: BaseAlgorithm, venv: VecEnv | None, sampling_seed: int | None = None):
    """A batch of observations -> their actions (most likely, or sampled), applying the observation normalisation."""
    norm = venv if isinstance(venv, VecNormalize) and venv.norm_obs else None
    predict = predictor(model, sampling_seed)

    def act(obs: np.ndarray) -> np.ndarray:
        return predict(norm.normalize_obs(obs) if norm is not None else obs)

    return act


def predictor(model: BaseAlgorithm, sampling_seed: int | None):
    """observations -> actions: the most likely; with a seed, sampled from draws of their own (torch's global
    random state, which training draws from, is left as it was)."""
    if sampling_seed is None:
        return partial(policy_actions, model.policy, deterministic=True)
    seeds = np.random.default_rng(sampling_seed)

    def sample(x):
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(int(seeds.integers(2**62)))
            return policy_actions(model.policy, x, deterministic=False)

    return sample


def policy_actions(policy: BasePolicy, obs, deterministic: bool) -> np.ndarray:
    """SB3's policy.predict for a batch, the same actions, without walking every module to set evaluation mode
    at each call (a third of a call's 0.4 ms): the mode is set only when training left it on."""
    if policy.training:
        policy.set_training_mode(False)
    obs_tensor, _ = policy.obs_to_tensor(obs)
    with torch.no_grad():
        actions = policy._predict(obs_tensor, deterministic=deterministic)
    actions = actions.cpu().numpy().reshape((-1, *policy.action_space.shape))
    if isinstance(policy.action_space, gym.spaces.Box):
        if policy.squash_output:
            return policy.unscale_action(actions)
        return np.clip(actions, policy.action_space.low, policy.action_space.high)
    return actions
