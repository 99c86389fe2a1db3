"""Make trajectories from a policy, and replay them in the compiled task to recompute everything."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..env.column_replay import Replayed, can_replay_columns, replay_columns
from ..spec import spec_hash, task_hash
from .episode import EpisodeRecord
from .loop import EpisodeRecorder, episode_steps
from .trajectory import Trajectory, TrajectoryError


def rollout_trajectory(
    env, policy: Callable, seed: int, meta: dict, on_reset: Callable | None = None
) -> tuple[Trajectory, np.ndarray]:
    """Run one episode and keep its portal coordinates and actions; also return the observations."""
    u = env.unwrapped
    times, coords, actions, observations, tools, bodies = [], [], [], [], [], []
    for step, (obs, _, info, action) in enumerate(episode_steps(env, seed, policy=policy, on_reset=on_reset)):
        if step:
            actions.append(np.asarray(action))
        times.append(info["time"] if step else 0.0)
        coords.append(u.portal_coordinates())
        tools.append(u.instrument_coordinates())
        bodies.append(u.body_poses())
        observations.append(obs)
    meta = {
        "spec": u.task_spec.name,
        "spec_hash": spec_hash(u.task_spec),
        "task_hash": task_hash(u.task_spec),
        "seed": seed,
        "subtasks": info["subtask"],
        "subtasks_total": info["subtasks_total"],
        **meta,
    }
    instruments = np.array(tools) if u.task.instruments else None
    loose = np.array(bodies) if u.loose is not None else None
    traj = Trajectory(np.array(times), np.array(coords), meta, np.array(actions), instruments, loose)
    return traj, np.array(observations)


def expert_trajectories(env, seeds) -> list[Trajectory]:
    """Scripted-expert demonstrations, one episode per seed."""
    from ..agents.expert import ScriptedExpert  # here: scoring a file needs no expert

    expert = ScriptedExpert(env)
    meta = {"source": "expert", "subject": "scripted-expert"}
    return [rollout_trajectory(env, expert.act, s, meta, expert.reset)[0] for s in seeds]


def check_ranges(env, traj: Trajectory) -> None:
    """Refuse a trajectory whose coordinates the env's portal cannot reach (TrajectoryError naming the first)."""
    problem = traj.range_problem(env.unwrapped.task.ranges)
    n = sum(len(t.qadr) for t in env.unwrapped.task.instruments)
    if traj.instruments is not None and traj.instruments.shape[1] != n:
        problem = f"instruments has {traj.instruments.shape[1]} coordinates per sample, the task's instruments {n}"
    k = len(env.unwrapped.loose.bodies) if env.unwrapped.loose is not None else 0
    if traj.bodies is not None and traj.bodies.shape[1] != k:
        problem = f"bodies has {traj.bodies.shape[1]} loose bodies per sample, the task {k}"
    if problem:
        raise TrajectoryError(problem)


def measured(traj: Trajectory) -> bool:
    """Whether a trajectory's poses are measurements with an error of their own (read off video frames, imported
    from a tracker's poses): its replay reads an avatar passed once the next is held (Task.read_past)."""
    return traj.meta.get("portal_from") == "video" or "imported_from" in traj.meta


def trajectory_steps(env, traj: Trajectory):
    """episode_steps replaying a trajectory: its poses (measured ones read past), instruments and bodies, its seed."""
    return episode_steps(
        env, traj.seed, portal=traj.portal, instruments=traj.instruments, bodies=traj.bodies, read_past=measured(traj)
    )


def replay(env, traj: Trajectory, on_sample: Callable | None = None) -> tuple[np.ndarray, list[dict], np.ndarray]:
    """Observations, infos and rewards of a trajectory, recomputed by placing the scope at each sample.

    `on_sample(env)`, if given, is called after each sample is placed (to read more of the state).
    """
    check_ranges(env, traj)
    observations, infos, rewards = [], [], []
    for obs, reward, info, _ in trajectory_steps(env, traj):
        if on_sample is not None:
            on_sample(env.unwrapped)
        observations.append(obs)
        infos.append(info)
        rewards.append(reward)
    return np.array(observations), infos, np.array(rewards)


def replay_arrays(env, traj: Trajectory) -> Replayed:
    """A recording's replay as scoring and learning read it (observations, rewards, tips, contacts, subtasks): by
    columns where the task allows it (env/column_replay.py: the same numbers in a third of the time), else step by
    step."""
    check_ranges(env, traj)
    if can_replay_columns(env):
        return replay_columns(env, traj.portal, traj.seed, measured(traj))
    tips = []
    obs, infos, rewards = replay(env, traj, lambda u: tips.append(u.state.tip_pos))
    contacts = np.array([i["contacts"] for i in infos])
    return Replayed(obs, rewards, np.array(tips), contacts, infos[-1]["subtask"], infos[-1]["subtasks_total"])


def replay_demonstrations(env, trajectories: list[Trajectory]):
    """For each trajectory with actions: its replayed observations (n+1), whether it completed the task, and its
    actions (n)."""
    for traj in trajectories:
        if traj.actions is None:
            continue
        done = replay_arrays(env, traj)
        n = min(len(done.observations) - 1, len(traj.actions))
        yield done.observations[: n + 1], done.success, traj.actions[:n]


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
    check_ranges(env, traj)
    rec = EpisodeRecorder(env, image_every=image_every, image=lambda u: u.render())
    observations = []
    for obs, reward, info, _ in trajectory_steps(env, traj):
        observations.append(obs)
        step = rec.snapshot(float(reward), info)
        if on_step is not None:
            on_step(step, env.unwrapped)
    return rec.record(traj.seed, traj.actions, info), np.array(observations)
