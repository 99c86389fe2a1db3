"""A warm start for PPO: clone the scripted expert, then DAgger rounds in which it labels the policy's states."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecEnv

from .bc import action_accuracy, behaviour_clone
from .expert import ScriptedExpert
from .sb3 import policy_function


@dataclass(frozen=True)
class Episodes:
    """Observations of some episodes, each labelled with the expert's action there, and the subtasks reached."""

    obs: np.ndarray
    labels: np.ndarray
    subtasks: float  # share of the subtasks the episodes completed


def labelled_episodes(
    env, expert: ScriptedExpert, seeds, act: Callable | None = None, expert_share: float = 0.0
) -> Episodes:
    """Episodes driven by `act(obs)` (None: the expert; else the expert at random steps, `expert_share` of them),
    every observation labelled with the expert's action."""
    obs_list, labels, done, total = [], [], 0, 0
    for seed in seeds:
        rng = np.random.default_rng(int(seed))
        obs, _ = env.reset(seed=int(seed))
        expert.reset()
        while True:
            label = expert.act(obs)
            obs_list.append(obs)
            labels.append(label)
            obs, _, terminated, truncated, info = env.step(
                label if act is None or rng.random() < expert_share else act(obs)
            )
            if terminated or truncated:
                break
        done, total = done + info["subtask"], total + info["subtasks_total"]
    return Episodes(np.array(obs_list), np.array(labels), done / max(total, 1))


def warm_start(
    model: BaseAlgorithm,
    venv: VecEnv,
    env,
    *,
    demonstrations: int,
    rounds: int,
    episodes: int,
    epochs: int,
    batch_size: int,
    learning_rate: float,
    expert_share: float,
    seed: int,
    log: Callable[[dict], None] | None = None,
) -> tuple[list[dict], Episodes]:
    """Clone `demonstrations` expert episodes into the model's policy, then `rounds` DAgger rounds of `episodes` of
    the deterministic policy's own episodes (the expert acting at random steps, `expert_share` ** round of them),
    labelled by the expert and added to the data, refitting on all of it.

    Episode seeds start at `seed` and are never reused; `log(row)` sees each round's row as it ends (round 0: the
    expert's episodes): pairs so far, the fit's last loss, the fitted policy's action accuracy on the round's
    episodes, the subtasks those episodes completed. Returns the rows and all the labelled data.
    """
    expert = ScriptedExpert(env)
    act = policy_function(model, venv)
    rows, obs, labels, next_seed = [], None, None, seed
    for k in range(rounds + 1):
        t0 = time.perf_counter()
        n = demonstrations if k == 0 else episodes
        new = labelled_episodes(env, expert, range(next_seed, next_seed + n), None if k == 0 else act, expert_share**k)
        next_seed += n
        obs = new.obs if obs is None else np.concatenate([obs, new.obs])
        labels = new.labels if labels is None else np.concatenate([labels, new.labels])
        losses = behaviour_clone(model, venv, obs, labels, epochs, batch_size, learning_rate, seed + k)
        row = {
            "dagger_round": k,
            "dagger_pairs": len(labels),
            "dagger_loss": losses[-1],
            "dagger_accuracy": action_accuracy(model, venv, new.obs, new.labels),
            "dagger_subtasks": new.subtasks,
            "dagger_seconds": time.perf_counter() - t0,
        }
        rows.append(row)
        if log is not None:
            log(row)
    return rows, Episodes(obs, labels, rows[-1]["dagger_subtasks"])
