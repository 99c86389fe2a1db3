"""Make trajectories from a policy, and replay them in the compiled task to recompute everything."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..agents.expert import ScriptedExpert
from ..spec import spec_hash, task_hash
from .episode import EpisodeRecord
from .trajectory import Trajectory


def rollout_trajectory(
    env, policy: Callable, seed: int, meta: dict, on_reset: Callable | None = None
) -> tuple[Trajectory, np.ndarray]:
    """Run one episode and keep its portal coordinates and actions; also return the observations."""
    u = env.unwrapped
    obs, _ = env.reset(seed=seed)
    if on_reset is not None:
        on_reset()
    times, coords, actions, observations = [0.0], [u.portal_coordinates()], [], [obs]
    done = False
    while not done:
        action = policy(obs)
        obs, _, term, trunc, info = env.step(action)
        actions.append(np.asarray(action))
        times.append(info["time"])
        coords.append(u.portal_coordinates())
        observations.append(obs)
        done = term or trunc
    meta = {
        "spec": u.task_spec.name,
        "spec_hash": spec_hash(u.task_spec),
        "task_hash": task_hash(u.task_spec),
        "seed": seed,
        "subtasks": info["subtask"],
        "subtasks_total": info["subtasks_total"],
        **meta,
    }
    return Trajectory(np.array(times), np.array(coords), meta, np.array(actions)), np.array(observations)


def expert_trajectories(env, seeds) -> list[Trajectory]:
    """Scripted-expert demonstrations, one episode per seed."""
    expert = ScriptedExpert(env)
    meta = {"source": "expert", "subject": "scripted-expert"}
    return [rollout_trajectory(env, expert.act, s, meta, expert.reset)[0] for s in seeds]


def replay(env, traj: Trajectory, on_sample: Callable | None = None) -> tuple[np.ndarray, list[dict], np.ndarray]:
    """Observations, infos and rewards of a trajectory, recomputed by placing the scope at each sample.

    `on_sample(env)`, if given, is called after each sample is placed (to read more of the state).
    """
    u = env.unwrapped
    obs, info = u.reset(seed=int(traj.meta.get("seed", 0)), options={"portal": traj.portal[0]})
    if on_sample is not None:
        on_sample(u)
    observations, infos, rewards = [obs], [info], [0.0]
    for q in traj.portal[1:]:
        obs, reward, term, trunc, info = u.replay_step(q)
        if on_sample is not None:
            on_sample(u)
        observations.append(obs)
        infos.append(info)
        rewards.append(reward)
        if term:
            break
    return np.array(observations), infos, np.array(rewards)


def replay_demonstrations(env, trajectories: list[Trajectory]):
    """For each trajectory with actions: its replayed observations (n+1), infos (n+1) and actions (n)."""
    for traj in trajectories:
        if traj.actions is None:
            continue
        obs, infos, _ = replay(env, traj)
        n = min(len(obs) - 1, len(traj.actions))
        yield obs[: n + 1], infos[: n + 1], traj.actions[:n]


def demonstration_pairs(env, trajectories: list[Trajectory]) -> tuple[np.ndarray, np.ndarray]:
    """(observation, action) pairs of trajectories with actions, observations recomputed by replay."""
    pairs = [(obs[:-1], actions) for obs, _, actions in replay_demonstrations(env, trajectories)]
    if not pairs:
        raise ValueError("no trajectory with actions to learn from")
    return np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])


def cue_events(infos: list[dict]) -> list[list]:
    """[step, kind, value] when the cue turns green or back ("green", bool) or a subtask completes ("subtask", n)."""
    events, green, subtask = [], None, None
    for step, info in enumerate(infos):
        if info["subtask"] != subtask:
            if subtask is not None:
                events.append([step, "subtask", int(info["subtask"])])
            subtask = info["subtask"]
        if bool(info["cue"]["green"]) != green:
            green = bool(info["cue"]["green"])
            events.append([step, "green", green])
    return events


def replay_episode(
    env, traj: Trajectory, image_every: int = 0, on_step: Callable | None = None
) -> tuple[EpisodeRecord, np.ndarray]:
    """A trajectory replayed as an EpisodeRecord (and its observations); `on_step(step, env)` sees each state."""
    u = env.unwrapped
    obs, info = u.reset(seed=int(traj.meta.get("seed", 0)), options={"portal": traj.portal[0]})
    shaft = u.model.body("scope_shaft").id
    length = u.task_spec.scope.shaft_length
    rows, images, observations = [], {}, []

    def snapshot(reward: float, info: dict, obs) -> None:
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
        observations.append(obs)
        step = len(rows) - 1
        if image_every and step % image_every == 0:
            images[step] = u.render()
        if on_step is not None:
            on_step(step, u)

    snapshot(0.0, info, obs)
    for q in traj.portal[1:]:
        obs, reward, term, _, info = u.replay_step(q)
        snapshot(float(reward), info, obs)
        if term:
            break
    cols = list(zip(*rows))
    names = u.feature_names
    feats = np.array(cols[6], float).reshape(len(rows), len(names))
    ep = EpisodeRecord(
        seed=int(traj.meta.get("seed", 0)),
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
        actions=traj.actions,
        images=images,
        subtasks_total=info["subtasks_total"],
        success=bool(info["success"]),
    )
    return ep, np.array(observations)
