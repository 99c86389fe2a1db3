"""Evaluation episodes: run a policy deterministically and record every step."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..data.episode import EpisodeRecord

Policy = Callable[[np.ndarray], object]


def record_episode(
    env, policy: Policy, seed: int, image_every: int = 0, on_reset: Callable | None = None
) -> EpisodeRecord:
    """Run one episode from `seed`; keep poses, rewards, features, cues and every k-th endoscope image."""
    u = env.unwrapped
    obs, info = env.reset(seed=seed)
    if on_reset is not None:
        on_reset()
    shaft = u.model.body("scope_shaft").id
    length = u.task_spec.scope.shaft_length
    rows, actions, images = [], [], {}

    def snapshot(reward: float, info: dict) -> None:
        s = u.state
        axis = u.data.xmat[shaft].reshape(3, 3)[:, 2]
        rows.append(
            (
                s.time,
                s.portal,
                s.tip_pos,
                s.tip_quat,
                u.data.xpos[shaft] - length * axis,
                reward,
                list(info["features"].values()),
                info["subtask"],
                info["cue"]["green"],
                info["contacts"],
            )
        )
        if image_every and (len(rows) - 1) % image_every == 0:
            images[len(rows) - 1] = u.render_views(outside=False)["endoscope"]

    snapshot(0.0, info)
    done = False
    while not done:
        action = policy(obs)
        obs, reward, term, trunc, info = env.step(action)
        actions.append(np.asarray(action))
        snapshot(float(reward), info)
        done = term or trunc
    cols = list(zip(*rows))
    names = u.feature_names
    feats = np.array(cols[6], float).reshape(len(rows), len(names))
    return EpisodeRecord(
        seed=seed,
        time=np.array(cols[0]),
        portal=np.array(cols[1]),
        tip_pos=np.array(cols[2]),
        tip_quat=np.array(cols[3]),
        shaft_end=np.array(cols[4]),
        reward=np.array(cols[5]),
        features={n: feats[:, i] for i, n in enumerate(names)},
        subtask=np.array(cols[7]),
        green=np.array(cols[8], bool),
        contacts=np.array(cols[9]),
        actions=np.array(actions),
        images=images,
        subtasks_total=info["subtasks_total"],
        success=bool(info["success"]),
    )


def summarize(episodes: list[EpisodeRecord]) -> dict:
    """Aggregate figures over evaluation episodes."""
    sums = [e.summary() for e in episodes]
    done = np.array([s["subtasks"] / max(1, s["subtasks_total"]) for s in sums])
    feats = {k: float(np.mean([s["features"][k] for s in sums])) for k in sums[0]["features"]} if sums else {}
    return {
        "episodes": len(sums),
        "success_rate": float(np.mean([s["success"] for s in sums])),
        "subtasks_completed": float(done.mean()),
        "return_mean": float(np.mean([s["return"] for s in sums])),
        "return_std": float(np.std([s["return"] for s in sums])),
        "episode_time_mean": float(np.mean([s["episode_time"] for s in sums])),
        "path_length_mean": float(np.mean([s["path_length"] for s in sums])),
        "features_mean": feats,
        "per_episode": sums,
    }


def evaluate(
    env,
    policy: Policy,
    seeds: list[int],
    image_every: int = 0,
    record: int = 0,
    on_reset: Callable | None = None,
    on_episode: Callable | None = None,
) -> tuple[dict, list[EpisodeRecord]]:
    """Deterministic episodes on the given seeds; images only for the first `record` episodes."""
    episodes = []
    for i, seed in enumerate(seeds):
        ep = record_episode(env, policy, seed, image_every if i < record else 0, on_reset)
        episodes.append(ep)
        if on_episode is not None:
            on_episode(i, ep)
    return summarize(episodes), episodes
