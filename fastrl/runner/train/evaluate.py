"""Evaluation episodes: run a policy deterministically and record every step."""

from __future__ import annotations

import weakref
from collections.abc import Callable

import numpy as np

from ...data.episode import EpisodeRecord
from ...data.loop import EpisodeRecorder, episode_steps
from ...env.images import EndoscopeFrames
from ...spec.images import Image

Policy = Callable[[np.ndarray], object]


def record_episode(
    env, policy: Policy, seed: int, image_every: int = 0, on_reset: Callable | None = None
) -> EpisodeRecord:
    """Run one episode from `seed`; keep poses, rewards, features, cues and every k-th endoscope image."""
    rec = EpisodeRecorder(env, image_every=image_every, image=endoscope_image)
    actions = []
    for step, (_, reward, info, action) in enumerate(episode_steps(env, seed, policy=policy, on_reset=on_reset)):
        if step:
            actions.append(np.asarray(action))
        rec.snapshot(float(reward), info)
    return rec.record(seed, np.array(actions), info)


_LEAN: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # each evaluation env's lean endoscope renderer


def endoscope_image(env) -> np.ndarray:
    """The recording's endoscope image at the env's size: drawn by the policy's lean renderer (half the time of the
    whole scene; 0.3% of pixels differ, by at most 2 levels) where the image is square and 32-128 px."""
    if env.width != env.height or not 32 <= env.width <= 128:
        return env.render()
    if env not in _LEAN:
        _LEAN[env] = EndoscopeFrames(task=env.task, model=env.model, image=Image(size=env.width, kind="rgb"))
    return _LEAN[env].frame(env.data, env.subtask).copy()


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


def evaluate_batched(envs: list, act: Callable[[np.ndarray], np.ndarray], seeds: list[int]) -> dict:
    """Deterministic episodes on the seeds, one env each, stepped in lockstep with one batched policy call.

    The cheap evaluation during training: subtask share, success, return and episode time, no records.
    `act` maps a batch of observations to a batch of actions; `envs` needs at least as many envs as seeds.
    """
    return batched_summary(batched_episodes(envs, act, seeds))


def batched_episodes(envs: list, act: Callable[[np.ndarray], np.ndarray], seeds: list[int]) -> np.ndarray:
    """evaluate_batched's episodes: (return, subtask share, success, time) per seed, in the seeds' order."""
    live = list(range(len(seeds)))
    obs = stack_observations([envs[i].reset(seed=s)[0] for i, s in enumerate(seeds)])
    out = np.zeros((len(seeds), 4))
    while live:
        actions = act({k: v[live] for k, v in obs.items()} if isinstance(obs, dict) else obs[live])
        still = []
        for i, action in zip(live, actions):
            o, reward, term, trunc, info = envs[i].step(action)
            out[i, 0] += reward
            for part, value in obs.items() if isinstance(obs, dict) else [(None, obs)]:
                value[i] = o if part is None else o[part]
            if term or trunc:
                out[i, 1:] = info["subtask"] / max(1, info["subtasks_total"]), float(info["success"]), info["time"]
            else:
                still.append(i)
        live = still
    return out


def batched_summary(episodes: np.ndarray) -> dict:
    """The figures of batched_episodes' rows."""
    returns, subtasks, success, times = episodes.T
    return {
        "success_rate": float(success.mean()),
        "subtasks_completed": float(subtasks.mean()),
        "return_mean": float(returns.mean()),
        "episode_time_mean": float(times.mean()),
    }


def stack_observations(observations: list):
    """Observations as one batch: an array, or a Dict's parts each stacked."""
    if isinstance(observations[0], dict):
        return {k: np.stack([o[k] for o in observations]) for k in observations[0]}
    return np.stack(observations)
