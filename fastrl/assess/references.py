"""Reference scores for normalising: a uniformly random policy (0) and the scripted expert (1), or, for a model
learned from recordings, the mean of those recordings (1)."""

from __future__ import annotations

import json
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..atomic import atomic_write
from ..data.recordings import load_recordings
from ..data.replay import expert_trajectories, rollout_trajectory
from ..spec import spec_hash, task_hash
from .scoring import NORMALISED, Scorer

REFERENCE_SEED = 90000  # held-out seeds, apart from training (0..), evaluation (10000..) and checks (20000..)


def reference_trajectories(
    scorer: Scorer, episodes: int, seed: int = REFERENCE_SEED, recordings: list | None = None
) -> dict[str, list]:
    """Random-policy trajectories on held-out seeds, and the scripted expert's on the same seeds (or `recordings`)."""
    env = scorer.env
    env.action_space.seed(seed)
    seeds = range(seed, seed + episodes)
    random = [
        rollout_trajectory(
            env, lambda _obs: env.action_space.sample(), s, {"source": "agent", "subject": "random-policy"}
        )[0]
        for s in seeds
    ]
    return {"random": random, "expert": expert_trajectories(env, seeds) if recordings is None else recordings}


def reference_scores(
    scorer: Scorer, episodes: int = 3, cache: Path | None = None, recordings: list | None = None
) -> dict:
    """Mean scores of each reference; read from / written to `cache` (a JSON file) when given. With `recordings`
    (trajectories), their mean is the upper reference instead of the scripted expert's."""
    key = {
        "task_hash": task_hash(scorer.spec),
        "episodes": episodes,
        "learned": scorer.learned,
        "reward_hash": _reward_identity(scorer),
        "scores": list(NORMALISED),
        "learned_sums": "per subtask reached",  # learned_scores divides them (caches before 2026-12-06 did not)
    }
    if recordings is not None:
        key["expert"] = sorted(f"{t.meta.get('subject', '')}:{t.meta.get('seed', 0)}" for t in recordings)
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
        + (
            "expert = the scripted expert (fastrl.agents.expert)"
            if recordings is None
            else f"expert = the {len(recordings)} recordings the model learned from"
        ),
    }
    for name, trajs in reference_trajectories(scorer, episodes, recordings=recordings).items():
        scored = [scorer.score(t) for t in trajs]
        out[name] = {
            k: (None if scored[0].scores[k] is None else float(np.mean([s.scores[k] for s in scored])))
            for k in (*NORMALISED, "subtasks", "path_length", "time", "smoothness")
        }
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_text(json.dumps(out, indent=2))
    return out


def learned_from(scorer: Scorer) -> list | None:
    """The recordings a run learned from (its `irl.demonstrations.path`), best heuristic return first; None when
    it learned from the scripted expert or from nothing: then the scripted expert is the reference."""
    folder = scorer.spec.irl.demonstrations.path
    if not scorer.learned or folder is None or not Path(folder).is_dir():
        return None
    recordings = [t for _, t in load_recordings([folder])[0]]
    if not recordings:
        return None
    heuristic = [scorer.score(t).scores["heuristic"] for t in recordings]
    return [recordings[i] for i in sorted(range(len(recordings)), key=lambda i: -heuristic[i])]


def references_for(scorer: Scorer, episodes: int, cache: Path | None) -> tuple[dict, list | None]:
    """The reference scores (see reference_scores) and the recordings learned from (see learned_from)."""
    recordings = learned_from(scorer)
    return reference_scores(scorer, episodes, cache, recordings), recordings


def _reward_identity(scorer: Scorer) -> str | None:
    """The saved reward network's checksum, so a cache never outlives the networks it scored with."""
    nets = scorer.networks
    return None if nets is None else getattr(nets, "identity", None)


def expert_paths(
    scorer: Scorer,
    seeds,
    cache: Path | None = None,
    compute: Callable | None = None,
    recordings: list | None = None,
) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """The scripted expert's (time, tip path) on each seed: the reference a trainee deviates from. With
    `recordings` (best first), the best recording on that seed, else the best of all, instead.

    With `cache` (an .npz), the expert's paths already computed for this spec are read from it and new ones added
    to it. `compute(seeds)` computes the missing ones (default: compute_expert_paths with this scorer)."""
    wanted = sorted(set(int(s) for s in seeds))
    if recordings is not None:
        return {seed: recorded_path(scorer, seed, recordings) for seed in wanted}
    key = spec_hash(scorer.spec)
    out = _read_paths(cache, key) if cache is not None else {}
    missing = [s for s in wanted if s not in out]
    if missing:
        out |= (compute or (lambda s: compute_expert_paths(scorer, s)))(missing)
    if cache is not None and missing:
        _write_paths(cache, key, out)
    return {s: out[s] for s in wanted}


def recorded_path(scorer: Scorer, seed: int, recordings: list) -> tuple[np.ndarray, np.ndarray]:
    """(time from 0, tip path) of the best recording on `seed`, else of the best of all."""
    traj = ([t for t in recordings if t.seed == seed] or recordings)[0]
    return traj.time - traj.time[0], scorer.tip_path(traj.portal)


def compute_expert_paths(scorer: Scorer, seeds) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Roll the scripted expert out on each seed: (time from 0, tip path)."""
    out = {}
    for seed in seeds:
        traj = expert_trajectories(scorer.env, [int(seed)])[0]
        out[int(seed)] = (traj.time - traj.time[0], scorer.tip_path(traj.portal))
    return out


def _read_paths(cache: Path, key: str) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Expert paths saved for the spec with hash `key`; none if the file is missing, broken or another spec's."""
    try:
        with np.load(cache, allow_pickle=False) as z:
            if str(z["spec_hash"]) != key:
                return {}
            return {int(n[5:]): (z[n], z["tip_" + n[5:]]) for n in z.files if n.startswith("time_")}
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):  # missing or broken: recomputed
        return {}


def _write_paths(cache: Path, key: str, paths: dict[int, tuple[np.ndarray, np.ndarray]]) -> None:
    """Save expert paths beside the spec hash, atomically (a reader never sees half a file)."""
    arrays = {"spec_hash": np.array(key)}
    for seed, (t, tip) in paths.items():
        arrays[f"time_{seed}"], arrays[f"tip_{seed}"] = t, tip
    cache.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(cache, lambda f: np.savez(f, **arrays))
