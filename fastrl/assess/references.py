"""Reference scores for normalising: a uniformly random policy (0) and the scripted expert (1)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..data.replay import expert_trajectories, rollout_trajectory
from ..spec import task_hash
from .scoring import NORMALISED, Scorer

REFERENCE_SEED = 90000  # held-out seeds, apart from training (0..), evaluation (10000..) and checks (20000..)


def reference_trajectories(scorer: Scorer, episodes: int, seed: int = REFERENCE_SEED) -> dict[str, list]:
    """Random-policy and scripted-expert trajectories on the same held-out seeds."""
    env = scorer.env
    env.action_space.seed(seed)
    seeds = range(seed, seed + episodes)
    random = [
        rollout_trajectory(
            env, lambda _obs: env.action_space.sample(), s, {"source": "agent", "subject": "random-policy"}
        )[0]
        for s in seeds
    ]
    return {"random": random, "expert": expert_trajectories(env, seeds)}


def reference_scores(scorer: Scorer, episodes: int = 3, cache: Path | None = None) -> dict:
    """Mean scores of each reference; read from / written to `cache` (a JSON file) when given."""
    key = {
        "task_hash": task_hash(scorer.spec),
        "episodes": episodes,
        "learned": scorer.learned,
        "reward_hash": _reward_identity(scorer),
        "scores": list(NORMALISED),
    }
    if cache is not None and cache.exists():
        try:
            saved = json.loads(cache.read_text())
            if saved.get("key") == key:
                return saved
        except (OSError, json.JSONDecodeError):
            pass  # a broken cache is recomputed
    out = {
        "key": key,
        "description": f"means over {episodes} episodes on seeds {REFERENCE_SEED}.."
        f"{REFERENCE_SEED + episodes - 1}: random = uniform random actions, "
        "expert = the scripted expert (fastrl.agents.expert)",
    }
    for name, trajs in reference_trajectories(scorer, episodes).items():
        scored = [scorer.score(t) for t in trajs]
        out[name] = {
            k: (None if scored[0].scores[k] is None else float(np.mean([s.scores[k] for s in scored])))
            for k in (*NORMALISED, "subtasks", "path_length", "time", "smoothness")
        }
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_text(json.dumps(out, indent=2))
    return out


def _reward_identity(scorer: Scorer) -> str | None:
    """The saved reward network's checksum, so a cache never outlives the networks it scored with."""
    nets = scorer.networks
    return None if nets is None else getattr(nets, "identity", None)


def expert_paths(scorer: Scorer, seeds) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """The scripted expert's (time, tip path) on each seed: the reference a trainee deviates from."""
    out = {}
    for seed in sorted(set(int(s) for s in seeds)):
        traj = expert_trajectories(scorer.env, [seed])[0]
        out[seed] = (traj.time - traj.time[0], scorer.tip_path(traj.portal))
    return out
