"""A trainee's video as portal coordinates: each frame read by the task's pose estimator, no tracker needed.

The estimator is trained once per task on the simulator's own frames (`pose_frames`) and kept in a cache keyed by
what the camera shows (the task's world without its cue), the frame size and the estimator's version; its held-out
error travels in every trajectory's meta."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.signal import savgol_filter

from ..cache import cache_dir
from ..spec import task_hash, world_hash
from ..spec.models import TaskSpec
from .pose_net import VERSION, PoseEstimator, downsample, fit, load, save
from .trajectory import Trajectory
from .video_import import endoscope_size, import_video

EPISODES = 360  # labelled episodes (about 45,000 frames) an estimator learns from (RESULTS: scores from video)
EPOCHS = 20
SMOOTH_S = 0.25  # the estimates are smoothed over this window (a quadratic Savitzky-Golay filter)


def estimator_name(spec: TaskSpec) -> str:
    """The file name of this task's estimator: the hash of its world, the frame size and the estimator's version."""
    w, h = endoscope_size(spec)
    return f"pose-{world_hash(spec)}-{w}x{h}-v{VERSION}.safetensors"


def train_estimator(env, *, seed: int = 0, episodes: int = EPISODES, epochs: int = EPOCHS, progress=None):
    """A PoseEstimator for the env's task; `progress(done, total, what)` as it renders and learns."""
    from .pose_frames import labelled_frames

    u, count, show = env.unwrapped, iter(range(1, episodes + 1)), progress or (lambda *_: None)
    inputs, portal = labelled_frames(
        env,
        episodes=episodes,
        seed=seed,
        reduce=downsample,
        on_episode=lambda: show(next(count), episodes, "rendering labelled frames"),
    )
    return fit(
        inputs,
        portal,
        size=(u.width, u.height),
        ranges=u.task.ranges,
        task_hash=task_hash(u.task_spec),
        seed=seed,
        epochs=epochs,
        on_epoch=lambda k, loss: show(k + 1, epochs, f"learning poses (loss {loss:.3f})"),
    )


def estimator_for(env, *, places: list[Path] = (), progress=None) -> tuple[PoseEstimator, Path]:
    """The task's estimator from the first of `places` (then the cache) that holds it, else trained and cached."""
    name = estimator_name(env.unwrapped.task_spec)
    for folder in [*places, cache_dir()]:
        if (Path(folder) / name).is_file():
            return load(Path(folder) / name), Path(folder) / name
    estimator = train_estimator(env, progress=progress)
    return estimator, save(estimator, cache_dir() / name)


def smooth(portal: np.ndarray, hz: float) -> np.ndarray:
    """Estimates smoothed over SMOOTH_S (angles unwrapped first); short trajectories are left as they are."""
    window = int(SMOOTH_S * hz) // 2 * 2 + 1
    if window < 5 or len(portal) < window:
        return portal
    out = portal.copy()
    out[:, 3:] = np.unwrap(out[:, 3:], axis=0)
    out = savgol_filter(out, window, 2, axis=0)
    out[:, 3:] = (out[:, 3:] + np.pi) % (2 * np.pi) - np.pi
    return out


def video_trajectory(path: Path, spec: TaskSpec, estimator: PoseEstimator, source: Path) -> Trajectory:
    """A video file (any size of the task's shape) as a trajectory of estimated portal coordinates on the control
    grid, no frames kept; VideoError names a file that cannot be read."""
    video = import_video(path, spec, scale=True)
    hz = spec.episode.control_hz
    portal = np.clip(smooth(estimator.portal(video.frames), hz), *estimator.ranges.T)
    meta = {**video.meta, "portal_from": "video", "pose_estimator": source.name, "pose_error": estimator.error}
    return Trajectory(video.time, portal, meta)
