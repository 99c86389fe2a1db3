"""Portal coordinates read off endoscope frames: labelled frames, the pose network, smoothing, the file split."""

import math

import numpy as np
import pytest

import fastrl
from fastrl.data import pose_net
from fastrl.data.pose_frames import labelled_frames
from fastrl.data.video_poses import estimator_for, estimator_name, smooth
from fastrl.runner.score.video_inputs import video_files

from ..conftest import spec_file

RANGES = np.array([[-1.0, 1.0], [-1.0, 1.0], [0.01, 0.15], [-math.pi, math.pi], [-math.pi, math.pi]])


def test_targets_and_coordinates_are_inverse_and_wrap_angles():
    rng = np.random.default_rng(0)
    portal = rng.uniform(RANGES[:, 0], RANGES[:, 1], (100, 5))
    back = pose_net.coordinates(pose_net.targets(portal, RANGES), RANGES)
    assert np.allclose(back, portal, atol=1e-5)
    assert np.all(np.abs(pose_net.coordinates(np.full((1, 7), 5.0), RANGES)[0, :3] - RANGES[:3, 1]) < 1e-9)  # clipped


def test_pose_errors_take_the_short_way_round():
    truth = np.array([[0.0, 0.0, 0.05, math.pi - 0.01, 0.0]])
    guess = np.array([[0.01, 0.0, 0.052, -math.pi + 0.01, 0.0]])
    e = pose_net.pose_errors(guess, truth)
    assert e["roll_deg"]["median"] == pytest.approx(math.degrees(0.02), rel=1e-3)
    assert e["insertion_mm"]["median"] == pytest.approx(2.0, rel=1e-3)
    assert e["pitch_deg"]["median"] == pytest.approx(math.degrees(0.01), rel=1e-3)


def test_smoothing_keeps_slow_motion_removes_jitter_and_stays_continuous_across_pi():
    t = np.arange(200) / 20
    slow = np.column_stack([0.1 * t, 0.2 * np.sin(0.3 * t), 0.05 + 0.001 * t, math.pi - 0.2 + 0.04 * t, 0 * t])
    slow[:, 3] = (slow[:, 3] + math.pi) % (2 * math.pi) - math.pi  # roll crosses pi
    jitter = np.random.default_rng(0).normal(0, 0.01, slow.shape)
    out = smooth(slow + jitter, 20)
    err = out - slow
    err[:, 3:] = (err[:, 3:] + math.pi) % (2 * math.pi) - math.pi
    assert np.abs(err).std() < 0.6 * jitter.std()
    assert np.all(np.abs(out[:, 3:]) <= math.pi + 1e-12)
    assert np.array_equal(smooth(slow[:3], 20), slow[:3])  # too short to smooth


def tiny_estimator(env):
    """Labelled frames of two episodes of the env's task and an estimator fitted to them for one epoch."""
    frames, portal = labelled_frames(env, episodes=2, seed=0)
    u, inputs = env.unwrapped, pose_net.downsample(frames)
    est = pose_net.fit(inputs, portal, size=(u.width, u.height), ranges=u.task.ranges, task_hash="t", seed=0, epochs=1)
    return frames, portal, est


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """Labelled frames of two TraceLines episodes at 64 px and an estimator fitted to them for one epoch."""
    env = fastrl.make(spec_file("tracelines"), width=64, height=64)
    return env, *tiny_estimator(env)


def test_labelled_frames_are_deterministic_in_range_and_show_different_views(tiny):
    env, frames, portal, _ = tiny
    assert frames.dtype == np.uint8 and frames.shape[1:] == (64, 64, 3) and len(frames) == len(portal) > 100
    ranges = env.unwrapped.task.ranges
    assert np.all(portal >= ranges[:, 0] - 1e-9) and np.all(portal <= ranges[:, 1] + 1e-9)
    assert frames.reshape(len(frames), -1).std(axis=0).mean() > 10  # the view changes along the episodes
    again_frames, again_portal = labelled_frames(env, episodes=2, seed=0)
    assert np.array_equal(again_portal, portal) and np.array_equal(again_frames, frames)
    inputs, reduced_portal = labelled_frames(env, episodes=2, seed=0, reduce=pose_net.downsample)
    assert inputs.shape == (len(frames), 3, 64, 64) and inputs.dtype == np.float16  # half the memory of float32
    assert np.array_equal(inputs, pose_net.downsample(frames)) and np.array_equal(reduced_portal, portal)


def test_an_estimator_saved_and_loaded_reads_the_same_and_refuses_other_sizes(tiny, tmp_path):
    _, frames, portal, est = tiny
    path = pose_net.save(est, tmp_path / "pose.safetensors")
    back = pose_net.load(path)
    assert np.allclose(back.portal(frames[:20]), est.portal(frames[:20]), atol=1e-6)
    assert np.array_equal(est.read(pose_net.downsample(frames[:20])), est.portal(frames[:20]))
    assert back.size == (64, 64) and back.error.keys() == est.error.keys() and "cable_deg" in back.error
    with pytest.raises(ValueError, match="the estimator reads"):
        est.portal(np.zeros((2, 32, 32, 3), np.uint8))
    (tmp_path / "bad.safetensors").write_bytes(b"no tensors here")
    with pytest.raises(ValueError, match="not a readable pose estimator"):
        pose_net.load(tmp_path / "bad.safetensors")


def test_the_estimator_is_found_in_a_given_place_before_the_cache(tiny, tmp_path, monkeypatch):
    env, _, _, est = tiny
    monkeypatch.setenv("FASTRL_CACHE", str(tmp_path / "cache"))
    name = estimator_name(env.unwrapped.task_spec)
    (tmp_path / "run").mkdir()
    pose_net.save(est, tmp_path / "run" / name)
    _, source = estimator_for(env, places=[tmp_path / "nowhere", tmp_path / "run"])
    assert source == tmp_path / "run" / name and not (tmp_path / "cache").exists()


def test_video_files_are_split_from_trajectories(tmp_path):
    videos, mixed, empty = tmp_path / "videos", tmp_path / "mixed", tmp_path / "empty"
    for d in (videos, mixed, empty):
        d.mkdir()
    (videos / "a.mp4").write_bytes(b"")
    (videos / "b.MOV").write_bytes(b"")
    (videos / "notes.txt").write_text("")
    (mixed / "c.mp4").write_bytes(b"")
    (mixed / "c.npz").write_bytes(b"")
    found, rest = video_files([videos, mixed, empty, tmp_path / "one.mkv", tmp_path / "t.npz"])
    assert found == [videos / "a.mp4", videos / "b.MOV", tmp_path / "one.mkv"]
    assert rest == [mixed, empty, tmp_path / "t.npz"]  # a folder with trajectories is a folder of trajectories
