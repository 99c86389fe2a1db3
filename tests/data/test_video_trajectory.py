"""Video in the trajectory contract: frames saved and loaded, put on the control grid, refused by replay and score."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.data import Trajectory, TrajectoryError
from fastrl.data.inverse import to_control_rate
from fastrl.data.replay import replay

from ..conftest import spec_file


def _frames(n: int, size: int = 8) -> np.ndarray:
    """n distinct frames: frame i is filled with the value i."""
    return np.repeat(np.arange(n, dtype=np.uint8), size * size * 3).reshape(n, size, size, 3)


def test_video_only_round_trip_keeps_frames_and_has_no_portal(tmp_path):
    t = Trajectory(np.arange(5) / 20, None, {"spec": "tracelines", "source": "human"}, frames=_frames(5))
    back = Trajectory.load(t.save(tmp_path / "v.npz"))
    assert back.portal is None and back.frames.dtype == np.uint8
    assert np.array_equal(back.frames, t.frames) and np.array_equal(back.time, t.time) and back.meta == t.meta
    with np.load(tmp_path / "v.npz") as z:
        assert "portal" not in z.files and z["frames"].shape == (5, 8, 8, 3)


def test_frames_beside_portal_round_trip(tmp_path):
    t = Trajectory(np.arange(3) / 20, np.zeros((3, 5)), {}, frames=_frames(3))
    back = Trajectory.load(t.save(tmp_path / "b.npz"))
    assert np.array_equal(back.portal, t.portal) and np.array_equal(back.frames, t.frames)


@pytest.mark.parametrize(
    "frames, why",
    [
        (None, "neither portal coordinates nor video frames"),
        (np.zeros((3, 8, 8, 3), np.float32), "frames must be uint8"),
        (np.zeros((2, 8, 8, 3), np.uint8), r"frames must have shape \(3, H, W, 3\)"),
        (np.zeros((3, 8, 8), np.uint8), r"frames must have shape \(3, H, W, 3\)"),
    ],
)
def test_bad_frames_are_named(frames, why):
    with pytest.raises(TrajectoryError, match=why):
        Trajectory(np.arange(3) / 20, None, {}, frames=frames)


def test_a_file_with_neither_portal_nor_frames_names_what_is_missing(tmp_path):
    np.savez(tmp_path / "x.npz", time=np.arange(3.0), meta=np.array(json.dumps({})))
    with pytest.raises(TrajectoryError, match=r"x.npz: missing arrays \['portal'\]"):
        Trajectory.load(tmp_path / "x.npz")


@pytest.mark.parametrize("fps", [25, 30, 60, 24, 13])
def test_frames_go_onto_the_control_grid_by_the_nearest_frame(fps):
    n = int(2.0 * fps) + 1  # 2 s of video
    t = Trajectory(np.arange(n) / fps, None, {}, frames=_frames(n, 2))
    on = to_control_rate(t, 20)
    assert len(on.time) == 41 and np.allclose(on.time, np.arange(41) / 20)
    nearest = np.ceil(np.arange(41) * fps / 20 - 0.5).astype(int)  # frame i is at i / fps; ties: the earlier
    assert np.array_equal(on.frames[:, 0, 0, 0], nearest)
    assert on.meta["resampled_from"] == n and on.portal is None


def test_video_only_trajectory_is_refused_by_replay():
    env = fastrl.make(spec_file("tracelines"))
    t = Trajectory(np.arange(3) / 20, None, {}, frames=_frames(3))
    with pytest.raises(TrajectoryError, match="video only"):
        replay(env, t)


def test_video_only_trajectory_is_refused_by_score_in_one_line_the_rest_scored(tmp_path):
    Trajectory(np.arange(5) / 20, None, {"spec": "tracelines"}, frames=_frames(5)).save(tmp_path / "v.npz")
    env = fastrl.make(spec_file("tracelines"))
    env.reset(seed=0)
    q = env.unwrapped.portal_coordinates()  # the scope held still where the episode starts
    Trajectory(np.arange(5) / 20, np.tile(q, (5, 1)), {"spec": "tracelines"}).save(tmp_path / "kinematic.npz")
    args = ["score", "--spec", str(spec_file("tracelines")), str(tmp_path), "--references", "1", "--no-pictures"]
    result = CliRunner().invoke(app, [*args, "-o", str(tmp_path / "out" / "scores.json"), "--no-progress"])
    assert result.exit_code == 0 and "scored 1 trajectories" in result.output and "1 skipped" in result.output
    lines = [line for line in result.output.splitlines() if "v.npz" in line]
    assert len(lines) == 1 and "video only" in lines[0] and "portal coordinates" in lines[0]
    assert "Traceback" not in result.output


def test_video_only_trajectory_is_refused_by_replay_command_naming_the_file(tmp_path):
    Trajectory(np.arange(5) / 20, None, {"spec": "tracelines"}, frames=_frames(5)).save(tmp_path / "v.npz")
    args = ["replay", str(tmp_path / "v.npz"), "--spec", str(spec_file("tracelines")), "--no-viewer"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2 and result.output.strip().count("\n") == 0
    assert result.output.startswith(f"{tmp_path / 'v.npz'}: is video only")


@pytest.mark.parametrize(
    "frames, why",
    [
        (np.zeros((3, 4, 4, 3), np.float64), "frames must be uint8"),
        (np.array([None, None, None], dtype=object), "pickle"),
    ],
)
def test_hostile_frames_in_a_file_are_named(tmp_path, frames, why):
    meta = np.array(json.dumps({}))
    np.savez(tmp_path / "h.npz", time=np.arange(3) / 20, meta=meta, frames=frames, allow_pickle=True)
    with pytest.raises(TrajectoryError, match=f"h.npz: .*{why}"):
        Trajectory.load(tmp_path / "h.npz")


def test_frames_declaring_a_huge_shape_are_refused_before_reading(tmp_path):
    header = np.lib.format.header_data_from_array_1_0(np.zeros((1, 1, 1, 3), np.uint8))
    header["shape"] = (100_000, 1024, 1024, 3)
    with open(tmp_path / "frames.npy", "wb") as f:
        np.lib.format.write_array_header_1_0(f, header)
    import zipfile

    with zipfile.ZipFile(tmp_path / "big.npz", "w") as z:
        z.write(tmp_path / "frames.npy", "frames.npy")
        z.writestr("time.npy", _npy(np.arange(3) / 20))
        z.writestr("meta.npy", _npy(np.array(json.dumps({}))))
    with pytest.raises(TrajectoryError, match="big.npz: frames declares shape"):
        Trajectory.load(tmp_path / "big.npz")


def _npy(a: np.ndarray) -> bytes:
    """The .npy bytes of an array."""
    import io

    buffer = io.BytesIO()
    np.save(buffer, a)
    return buffer.getvalue()
