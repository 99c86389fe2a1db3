"""Trajectories with actions to and from Minari datasets (the Gymnasium ecosystem's offline-RL format), on disk only.

An episode holds the observations and heuristic rewards recomputed by replay, the recorded actions, and in its infos
the portal coordinates and times (and, where recorded, the instruments' coordinates and the loose bodies' poses,
flattened per sample), so importing gives back the same trajectories; each episode's trajectory metadata is kept as
JSON in the episode metadata under "fastrl". The dataset's env_spec makes the very task it was replayed in
(`minari.load_dataset(id).recover_environment()`), whether or not its spec is bundled.
"""

from __future__ import annotations

import json
import os
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..about import DISTRIBUTION, installed_version
from .trajectory import Trajectory, TrajectoryError

META_KEY = "fastrl"


@contextmanager
def _datasets_root(root: Path):
    """MINARI_DATASETS_PATH set to a local folder for the duration (Minari resolves dataset ids under it)."""
    old = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(Path(root).resolve())
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = old


def episode_buffer(env, traj: Trajectory, index: int):
    """One trajectory replayed as a Minari EpisodeBuffer (observations T, actions, rewards, ends T-1)."""
    from minari.data_collector import EpisodeBuffer

    from .replay import trajectory_steps

    observations, rewards, term = [], [], False
    for obs, reward, info, _ in trajectory_steps(env, traj):
        observations.append(obs)
        rewards.append(float(reward))
        term = bool(info["success"])
    rewards = rewards[1:]
    n = len(observations)
    infos = {"time": np.asarray(traj.time[:n], np.float64)[:, None], "portal": np.asarray(traj.portal[:n], np.float64)}
    if traj.instruments is not None:
        infos["instruments"] = np.asarray(traj.instruments[:n], np.float64)
    if traj.bodies is not None:
        infos["bodies"] = np.asarray(traj.bodies[:n], np.float64).reshape(n, -1)  # (T, k * 7): arrow keeps 2-D
    ends = np.zeros(n - 1, bool)
    terminations, truncations = ends.copy(), ends.copy()
    terminations[-1], truncations[-1] = bool(term), not term
    return EpisodeBuffer(
        id=index,
        seed=traj.seed,
        observations=np.asarray(observations, np.float32),
        actions=np.asarray(traj.actions[: n - 1]),
        rewards=rewards,
        terminations=terminations.tolist(),
        truncations=truncations.tolist(),
        infos=infos,  # time as (T, 1): Minari 0.5.4's arrow storage cannot decode a per-step scalar info
    )


def env_spec(task_spec):
    """A Gymnasium EnvSpec of this very task: the id registered for its name, the resolved spec as plain kwargs.

    `fastrl:make` takes the spec as a dict, so the env recovers without the spec file (a spec that is not bundled,
    or a bundled one edited since); Minari stores the EnvSpec as JSON, which the plain dict survives.
    """
    from gymnasium.envs.registration import EnvSpec

    from .. import TASK_IDS

    task = {name: task for task, name in TASK_IDS.items()}.get(task_spec.name, task_spec.name)
    return EnvSpec(f"fastrl/{task}-v0", entry_point="fastrl:make", kwargs={"spec": task_spec.model_dump(mode="json")})


def export_minari(
    env, trajectories: list[Trajectory], root: Path, dataset_id: str, description: str | None = None
) -> Path:
    """Write trajectories (all with actions, all of env's task) as the Minari dataset `dataset_id` under `root`."""
    import minari

    missing = [i for i, t in enumerate(trajectories) if t.actions is None]
    if missing:
        raise TrajectoryError(f"trajectories {missing[:5]} have no actions: a Minari dataset needs actions")
    if not trajectories:
        raise TrajectoryError("no trajectories to export")
    buffers = [episode_buffer(env, t, i) for i, t in enumerate(trajectories)]
    version = installed_version()
    with _datasets_root(root), warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=UserWarning, module="minari")  # advice on optional fields
        dataset = minari.create_dataset_from_buffers(
            dataset_id,
            buffers,
            env=env_spec(env.unwrapped.task_spec),
            observation_space=env.observation_space,
            action_space=env.action_space,
            algorithm_name="fastrl replay of recorded trajectories",
            author="fastrl",
            description=description or f"{len(buffers)} trajectories of {env.unwrapped.task_spec.name}",
            data_format="arrow",
            requirements=[f"{DISTRIBUTION}=={version}"] if version else None,
        )
        dataset.storage.update_episode_metadata([{META_KEY: json.dumps(t.meta)} for t in trajectories])
        return Path(dataset.storage.data_path).parent


def find_dataset(path: Path) -> Path:
    """The Minari data folder (holding metadata.json) at or below `path`, or a clear error."""
    path = Path(path)
    found = [path / "data"] if (path / "data" / "metadata.json").is_file() else []
    found = found or [p.parent for p in sorted(path.glob("**/data/metadata.json"))]
    if (path / "metadata.json").is_file():
        found = [path]
    if len(found) != 1:
        what = "no Minari dataset" if not found else f"{len(found)} Minari datasets ({', '.join(map(str, found))})"
        raise FileNotFoundError(f"{path}: {what}; give the folder of one dataset")
    return found[0]


def import_minari(path: Path) -> list[Trajectory]:
    """The trajectories of a Minari dataset that fastrl exported (portal coordinates and times in the infos)."""
    from minari import MinariDataset

    data = find_dataset(path)
    dataset = MinariDataset(data)
    metas = list(dataset.storage.get_episode_metadata(dataset.episode_indices))
    out = []
    for episode, meta in zip(dataset.iterate_episodes(), metas):
        infos = episode.infos or {}
        if "portal" not in infos or "time" not in infos:
            raise TrajectoryError(f"{data}: episode {episode.id} has no portal coordinates in its infos")
        extra = json.loads(meta[META_KEY]) if META_KEY in meta else {"source": "agent"}
        try:
            time = np.asarray(infos["time"]).reshape(-1)
            tools = np.asarray(infos["instruments"]) if "instruments" in infos else None
            bodies = np.asarray(infos["bodies"]).reshape(len(time), -1, 7) if "bodies" in infos else None
            out.append(Trajectory(time, infos["portal"], extra, np.asarray(episode.actions), tools, bodies))
        except TrajectoryError as e:
            raise TrajectoryError(f"{data}: episode {episode.id}: {e}") from None
    return out
