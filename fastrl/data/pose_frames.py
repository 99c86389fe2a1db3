"""Endoscope frames labelled with the portal coordinates that made them: what a video's pose estimator learns from.

Two kinds of episode, replayed in the compiled task and rendered as its recordings are: the scripted expert's
paths wandered off by slow random offsets (the task's states, its avatars done in every order), and slow random
sweeps over the portal's whole range (the views no expert takes). Every episode then goes through the video codec
at a random quality and size, as a trainee's video would."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from .loop import episode_steps
from .replay import expert_trajectories
from .video import read_video, write_video

# offsets of the wandering expert: pitch, yaw (rad), insertion (m), roll, cable (rad)
WANDER = np.array([0.15, 0.15, 0.02, 0.8, 0.8])
SWEEP_SECONDS = 8.0
CRF = (18, 38)  # the codec's quality, drawn per episode
SCALES = (0.5, 0.75, 1.0, 1.5)  # the video's size as a share of the endoscope image's, drawn per episode


def slow_curves(rng: np.random.Generator, n: int, hz: float, amplitude: np.ndarray) -> np.ndarray:
    """(n, 5) sums of three sinusoids per coordinate, 0.05-0.5 Hz, each coordinate within +- its amplitude."""
    t = np.arange(n)[:, None, None] / hz
    freq = rng.uniform(0.05, 0.5, (1, 3, 5))
    phase = rng.uniform(0, 2 * np.pi, (1, 3, 5))
    weight = rng.dirichlet(np.ones(3), 5).T[None]
    return amplitude * (weight * np.sin(2 * np.pi * freq * t + phase)).sum(axis=1)


def wandering_expert(rng: np.random.Generator, portal: np.ndarray, hz: float, ranges: np.ndarray) -> np.ndarray:
    """An expert's coordinates plus slow random offsets, kept in the portal's range."""
    return np.clip(portal + slow_curves(rng, len(portal), hz, WANDER * rng.uniform(0.2, 1.0)), *ranges.T)


def sweep(rng: np.random.Generator, hz: float, ranges: np.ndarray) -> np.ndarray:
    """Slow random curves over the portal's whole range, from a random pose."""
    centre = rng.uniform(ranges[:, 0], ranges[:, 1])
    curves = centre + slow_curves(rng, int(SWEEP_SECONDS * hz), hz, ranges[:, 1] - ranges[:, 0])
    return np.clip(curves, *ranges.T)


def task_paths(env, seeds) -> list[np.ndarray]:
    """The scripted expert's coordinates per seed; for a task without one, each seed's start pose held still."""
    u = env.unwrapped
    try:
        if u.task_spec.evaluate.expert:
            return [t.portal for t in expert_trajectories(env, seeds)]
    except RuntimeError:  # a task the scripted expert cannot do
        pass
    steps, held = int(SWEEP_SECONDS * u.task_spec.episode.control_hz), []
    for s in seeds:
        u.reset(seed=s)
        held.append(np.repeat(u.portal_coordinates()[None], steps, axis=0))
    return held


def rendered(env, portal: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(frames, coordinates) of coordinates replayed until they end or the task is done."""
    u, frames, coords = env.unwrapped, [], []
    for _ in episode_steps(env, seed, portal=portal):
        frames.append(u.render())
        coords.append(u.portal_coordinates())
    return np.stack(frames), np.array(coords)


def through_codec(rng: np.random.Generator, frames: np.ndarray, hz: float) -> np.ndarray:
    """The frames after an H.264 round trip at a random quality and size, read back at their own size."""
    h, w = frames.shape[1:3]
    scale = rng.choice(SCALES)
    size = (max(64, int(w * scale) // 2 * 2), max(64, int(h * scale) // 2 * 2))  # x264 varies run to run below
    with tempfile.TemporaryDirectory() as tmp:
        path = write_video(Path(tmp) / "v.mp4", frames, hz, crf=int(rng.integers(*CRF)), size=size)
        return read_video(path, (w, h)).frames[: len(frames)]


def labelled_frames(env, *, episodes: int, seed: int, reduce=None, on_episode=None) -> tuple[np.ndarray, np.ndarray]:
    """(N, H, W, 3) uint8 frames and (N, 5) portal coordinates from `episodes` episodes, three in four wandering
    experts, one in four a sweep; `reduce(frames)` applied to each episode's frames as they come (so that full-size
    frames never pile up), `on_episode()` after each."""
    u = env.unwrapped
    hz, ranges = u.task_spec.episode.control_hz, u.task.ranges
    rng = np.random.default_rng(seed)
    paths = task_paths(env, range(seed, seed + episodes))
    frames, coords = [], []
    for k in range(episodes):
        if k % 4:
            portal = wandering_expert(rng, paths[k], hz, ranges)
        else:
            portal = sweep(rng, hz, ranges)
        f, q = rendered(env, portal, seed + k)
        f = through_codec(rng, f, hz)
        frames.append(f if reduce is None else reduce(f))
        coords.append(q)
        if on_episode is not None:
            on_episode()
    return np.concatenate(frames), np.concatenate(coords)
