"""Endoscope video in and out: real MuJoCo rendering, real H.264 encoding and decoding (PyAV), tiny budgets."""

import subprocess
import sys

import av
import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.data import Trajectory
from fastrl.data.render_video import at_rate, rendered_frames
from fastrl.data.replay import expert_trajectories
from fastrl.data.video import VideoError, read_video, write_video

from ..conftest import spec_file

SIZE = 64
SPEC = str(spec_file("tracelines"))
AT_SIZE = ["--set", f"evaluate.image_size=[{SIZE},{SIZE}]"]  # the task's endoscope size for import-video
MAE = 4.0  # mean absolute error (0-255) that H.264 at crf 23 leaves on these frames


def run(*args):
    """The CLI's exit code and its stdout and stderr together."""
    result = CliRunner().invoke(app, [str(a) for a in args])
    return result.exit_code, result.output


@pytest.fixture(scope="module")
def expert(tmp_path_factory):
    """A 2 s scripted-expert trajectory (41 samples at 20 Hz), its file and its endoscope frames at 64 px."""
    env = fastrl.make(spec_file("tracelines"), width=SIZE, height=SIZE)
    full = expert_trajectories(env, [0])[0]
    traj = Trajectory(full.time[:41], full.portal[:41], full.meta)
    path = traj.save(tmp_path_factory.mktemp("expert") / "expert.npz")
    time, frames = rendered_frames(env, traj)
    return traj, path, frames


def mae(a, b) -> float:
    """Mean absolute difference of two uint8 arrays."""
    return float(np.abs(a.astype(int) - b.astype(int)).mean())


def test_rendered_frames_show_the_scope_moving(expert):
    _, _, frames = expert
    assert frames.shape == (41, SIZE, SIZE, 3) and frames.dtype == np.uint8
    assert frames.std() > 10 and mae(frames[0], frames[-1]) > 2  # a picture, and it changes


def test_render_and_import_round_trip(expert, tmp_path):
    traj, path, frames = expert
    code, output = run("render-video", path, "--spec", SPEC, "--size", f"{SIZE}x{SIZE}", "-o", tmp_path / "e.mp4")
    assert code == 0, output
    video = read_video(tmp_path / "e.mp4")
    assert video.frames.shape == frames.shape and video.fps == 20 and np.allclose(video.time, np.arange(41) / 20)
    code, output = run("import-video", tmp_path / "e.mp4", "--spec", SPEC, *AT_SIZE, "-o", tmp_path / "back.npz")
    assert code == 0, output
    back = Trajectory.load(tmp_path / "back.npz")
    assert back.portal is None and back.frames.shape == frames.shape
    assert np.allclose(back.time, traj.time - traj.time[0]) and mae(back.frames, frames) < MAE
    assert mae(back.frames[1:], frames[:-1]) > mae(back.frames, frames)  # each frame matches its own tick best
    m = back.meta
    assert (m["subject"], m["video_fps"], m["video_size"], m["video_frames"]) == ("e", 20, [SIZE, SIZE], 41)
    assert m["task_hash"] == traj.meta["task_hash"] and m["source"] == "human"


@pytest.mark.parametrize("fps, size", [(25, SIZE), (30, SIZE), (60, SIZE), (20, 96), (30, 128)])
def test_reencodes_land_on_the_same_control_grid(expert, tmp_path, fps, size):
    _, _, frames = expert
    time = np.arange(41) / 20
    mp4 = write_video(tmp_path / f"r{fps}.mp4", at_rate(time, frames, fps), fps, crf=28, size=(size, size))
    code, output = run("import-video", mp4, "--spec", SPEC, *AT_SIZE, "--scale", "-o", tmp_path / "r.npz")
    assert code == 0, output
    back = Trajectory.load(tmp_path / "r.npz")
    assert len(back.time) == 41 and np.allclose(back.time, time) and back.meta["video_fps"] == fps
    assert mae(back.frames, frames) < 1.5 * MAE


def _audio_only(path):
    """An mp4 holding one second of silence (AAC) and no video."""
    with av.open(str(path), "w") as c:
        stream = c.add_stream("aac", rate=8000)
        stream.layout = "mono"
        for i in range(8):
            frame = av.AudioFrame.from_ndarray(np.zeros((1, 1024), np.float32), format="fltp", layout="mono")
            frame.sample_rate, frame.pts = 8000, i * 1024
            c.mux(stream.encode(frame))
        c.mux(stream.encode(None))


def _faststart(path, frames):
    """An mp4 with its index first (movflags faststart): cut short, its header still declares every frame."""
    with av.open(str(path), "w", options={"movflags": "+faststart"}) as c:
        stream = c.add_stream("libx264", rate=20)
        stream.width, stream.height, stream.pix_fmt = SIZE, SIZE, "yuv420p"
        for i, rgb in enumerate(frames):
            frame = av.VideoFrame.from_ndarray(rgb, format="rgb24")
            frame.pts = i
            c.mux(stream.encode(frame))
        c.mux(stream.encode(None))


def test_bad_videos_are_named_and_skipped_the_rest_imported(expert, tmp_path):
    _, _, frames = expert
    d = tmp_path / "videos"
    good = write_video(d / "good.mp4", frames, 20).read_bytes()
    (d / "truncated.mp4").write_bytes(good[: len(good) // 2])
    (d / "empty.mp4").write_bytes(b"")
    (d / "corrupt.mp4").write_bytes(np.random.default_rng(0).bytes(4000))
    _audio_only(d / "audio.mp4")
    write_video(d / "small.mp4", frames[:, ::2, ::2], 20)  # another size, --scale not given
    _faststart(tmp_path / "fs.mp4", frames)
    (d / "cut.mp4").write_bytes((tmp_path / "fs.mp4").read_bytes()[:-6000])
    code, output = run("import-video", d, "--spec", SPEC, *AT_SIZE, "-o", tmp_path / "out", "--no-progress")
    assert code == 2 and "Traceback" not in output
    expected = {
        "truncated": "corrupt or truncated",
        "empty": "empty file",
        "corrupt": "not a readable video",
        "audio": "audio only",
        "small": f"32x32, the task's endoscope images are {SIZE}x{SIZE}",
        "cut": "corrupt or truncated",
    }
    for name, why in expected.items():
        lines = [line for line in output.splitlines() if f"{name}.mp4" in line]
        assert len(lines) == 1 and line_says(lines[0], why), (name, output)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["good.npz"]  # nothing else, no temporary file
    assert "imported 1 videos" in output and "6 skipped" in output


def line_says(line: str, why: str) -> bool:
    """Whether a message line starts with `skipped` and holds the reason."""
    return line.startswith("skipped ") and why in line


def test_reading_names_the_fault_directly(tmp_path):
    with pytest.raises(VideoError, match="missing.mp4: cannot read file"):
        read_video(tmp_path / "missing.mp4")
    with pytest.raises(VideoError, match="even width and height"):
        write_video(tmp_path / "odd.mp4", np.zeros((2, 9, 9, 3), np.uint8), 20)
    assert not list(tmp_path.iterdir())  # a refused write leaves nothing


@pytest.mark.parametrize("size", [None, (96, 96), (48, 48)])
def test_encoding_is_deterministic(expert, tmp_path, size):
    _, _, frames = expert
    written = {write_video(tmp_path / f"{k}.mp4", frames[:20], 20, crf=33, size=size).read_bytes() for k in range(3)}
    assert len(written) == 1


# renders a sweep in a fresh process, then encodes it as the pose estimator's training does, and prints the hash
RENDER_THEN_ENCODE = """
import hashlib, sys, tempfile
from pathlib import Path
import numpy as np
import fastrl
from fastrl.data import pose_frames
from fastrl.data.video import write_video
env = fastrl.make(sys.argv[1], width=128, height=128)
sweep = pose_frames.sweep(np.random.default_rng(0), 20.0, env.unwrapped.task.ranges)
frames, _ = pose_frames.rendered(env, sweep, 0)
with tempfile.TemporaryDirectory() as tmp:
    print(hashlib.sha256(write_video(Path(tmp) / "v.mp4", frames, 20, crf=33, size=(96, 96)).read_bytes()).hexdigest())
"""


def test_processes_that_render_then_encode_write_the_same_bytes():
    # x264's macroblock tree gave other bytes in about one such process of two: four side by side catch it
    runs = [
        subprocess.Popen([sys.executable, "-c", RENDER_THEN_ENCODE, SPEC], stdout=subprocess.PIPE, text=True)
        for _ in range(4)
    ]
    hashes = [r.communicate(timeout=300)[0].strip() for r in runs]
    assert all(r.returncode == 0 for r in runs) and all(hashes)
    assert len(set(hashes)) == 1


def test_render_many_names_bad_trajectories_and_records_rerun(expert, tmp_path):
    traj, path, frames = expert
    d = tmp_path / "trajs"
    d.mkdir()
    (d / "a.npz").write_bytes(path.read_bytes())
    (d / "broken.npz").write_bytes(b"not a zip")
    Trajectory(traj.time[:5], None, {"spec": "tracelines"}, frames=frames[:5]).save(d / "video_only.npz")
    rrd = tmp_path / "v.rrd"
    code, output = run("render-video", d, "--size", f"{SIZE}x{SIZE}", "-o", tmp_path / "out", "--rrd", rrd)
    assert code == 2 and "Traceback" not in output
    assert [line for line in output.splitlines() if "broken.npz" in line][0].startswith("skipped ")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["a.mp4", "video_only.mp4"]
    assert mae(read_video(tmp_path / "out" / "video_only.mp4").frames, frames[:5]) < MAE  # its own frames
    verify = subprocess.run(["rerun", "rrd", "verify", str(rrd)], capture_output=True, text=True)
    assert verify.returncode == 0 and "1 file verified" in verify.stdout + verify.stderr
    from rerun.chunk import RrdReader

    entities = {chunk.entity_path for chunk in RrdReader(str(rrd)).stream()}
    assert {"/videos/a", "/videos/video_only"} <= entities


def test_demos_write_a_video_beside_each_trajectory(tmp_path):
    code, output = run("demos", "--expert", SPEC, "-n", "1", "-o", tmp_path, "--video", "--no-progress")
    assert code == 0, output
    npz, mp4 = sorted(tmp_path.glob("*.npz")), sorted(tmp_path.glob("*.mp4"))
    assert [p.stem for p in npz] == [p.stem for p in mp4]
    assert len(read_video(mp4[0]).time) == len(Trajectory.load(npz[0]).time)


def test_cohort_writes_a_video_beside_each_trajectory(tmp_path):
    short = ["--set", "episode.time_limit=2", "--set", "evaluate.image_size=[32,32]"]
    code, output = run("cohort", SPEC, "--levels", 2, "--per-level", 1, "-o", tmp_path, "--video", *short)
    assert code == 0, output
    for npz in sorted(tmp_path.glob("*.npz")):
        video = read_video(npz.with_suffix(".mp4"))
        assert video.size == (32, 32) and len(video.time) == len(Trajectory.load(npz).time)


def test_av1_renders_quietly_and_reads_back(expert, tmp_path, capfd):
    _, path, frames = expert
    rrd = tmp_path / "a.rrd"
    code, output = run(
        "render-video", path, "--size", f"{SIZE}x{SIZE}", "--codec", "av1", "-o", tmp_path / "a.mp4", "--rrd", rrd
    )
    assert code == 0, output
    video = read_video(tmp_path / "a.mp4")
    assert video.codec == "libdav1d" and len(video.time) == len(frames) and mae(video.frames, frames) < MAE
    assert "Svt" not in capfd.readouterr().err  # the encoder's banner stays off the terminal
    verify = subprocess.run(["rerun", "rrd", "verify", str(rrd)], capture_output=True, text=True)
    assert verify.returncode == 0
    code, output = run("render-video", path, "--codec", "av1", "--crf", 64, "-o", tmp_path / "b.mp4")
    assert code == 2 and "--crf in [0, 63] for av1" in output and not (tmp_path / "b.mp4").exists()
