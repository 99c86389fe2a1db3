"""The endoscope video of a trajectory: its recorded frames, or its portal coordinates replayed and rendered."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .frames import control_grid, nearest_rows
from .inverse import to_control_rate
from .replay import check_ranges, trajectory_steps
from .trajectory import Trajectory
from .video import write_video


def rendered_frames(env, traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """(time, frames): the trajectory replayed on the env's control grid, the endoscope rendered at every sample
    (at the env's width and height) until the samples end or the task is done."""
    traj = to_control_rate(traj, env.unwrapped.task_spec.episode.control_hz)
    check_ranges(env, traj)
    u, frames = env.unwrapped, []
    for _ in trajectory_steps(env, traj):
        frames.append(u.render())
    return traj.time[: len(frames)] - traj.time[0], np.stack(frames)


def trajectory_frames(env, traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """(time from 0, frames) of a trajectory: the frames it carries, else its replay rendered in `env`."""
    if traj.frames is not None:
        return traj.time - traj.time[0], traj.frames
    return rendered_frames(env, traj)


def at_rate(time: np.ndarray, frames: np.ndarray, fps: float) -> np.ndarray:
    """Frames at t = k / fps from 0 to the last time, each the nearest in time (ties: the earlier)."""
    return nearest_rows(control_grid(time, fps), time, frames)


def write_trajectory_video(
    env,
    traj: Trajectory,
    path: Path,
    *,
    fps: float | None = None,
    size: tuple[int, int] | None = None,
    crf: int = 23,
    codec: str = "h264",
) -> tuple[Path, int]:
    """Write a trajectory's endoscope video (at `fps`, default the control rate; scaled to `size`) as an mp4;
    return the path and the number of frames."""
    time, frames = trajectory_frames(env, traj)
    fps = fps or env.unwrapped.task_spec.episode.control_hz
    frames = at_rate(time, frames, fps) if len(time) > 1 else frames
    return write_video(path, frames, fps, crf=crf, size=size, codec=codec), len(frames)
