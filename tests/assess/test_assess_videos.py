"""`fastrl assess VIDEOS/` and `fastrl score --run RUN VIDEOS/`: the protocol from endoscope videos alone."""

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.data import Trajectory, pose_net, video_poses
from fastrl.data.cohort import make_cohort
from fastrl.data.render_video import write_trajectory_video
from fastrl.data.video_poses import estimator_name
from fastrl.runner.score.video_inputs import VIDEO_CENTRING
from fastrl.spec import load_spec

from ..data.test_video_poses import tiny_estimator
from ..runner.test_runner import rrd_verify

pytestmark = pytest.mark.slow  # trains end to end

NO_EXPERT = Path(__file__).parents[1] / "fixtures" / "no_expert.yaml"
AT_64 = ["evaluate.image_size=[64,64]"]


@pytest.fixture(scope="module")
def videos(tmp_path_factory):
    """Three trainees' endoscope videos at 64 px (one per level), a corrupt and an empty file beside them, and a
    pose estimator for the task fitted for one epoch, in a cache of its own."""
    root = tmp_path_factory.mktemp("videos")
    spec = load_spec(NO_EXPERT, AT_64)
    env = fastrl.make(spec, width=64, height=64)
    folder = root / "videos"
    for traj in make_cohort(spec, 3, 1, seed=0):
        write_trajectory_video(env, traj, folder / f"{traj.meta['subject']}.mp4")
    (folder / "corrupt.mp4").write_bytes(np.random.default_rng(0).bytes(3000))
    (folder / "empty.mp4").write_bytes(b"")
    _, _, est = tiny_estimator(env)
    pose_net.save(est, root / "cache" / estimator_name(spec))
    return folder, root / "cache"


def test_assess_learns_from_videos_alone_and_scores_them_later(videos, tmp_path, monkeypatch):
    folder, cache = videos
    monkeypatch.setenv("FASTRL_CACHE", str(cache))
    out = tmp_path / "report" / "scores.json"
    res = CliRunner().invoke(
        app,
        ["assess", str(folder), "--spec", str(NO_EXPERT), "--set", AT_64[0], "--top", "2", "--by", "time"]
        + ["-o", str(out), "--runs", str(tmp_path), "--no-progress"],
    )
    assert res.exit_code == 0, res.output
    assert "learned from the 2 best of 3 recordings" in res.output
    skipped = [line for line in res.output.splitlines() if line.startswith("skipped")]
    assert len(skipped) == 2 and any("corrupt.mp4" in s for s in skipped) and any("empty.mp4" in s for s in skipped)
    report = json.loads(out.read_text())
    assert sorted(r["file"] for r in report["trajectories"]) == ["L1-S01", "L2-S01", "L3-S01"]
    assert report["trajectories"][0]["reward"] is not None and report["trajectories"][0]["value"] is not None
    rrd_verify(out.with_suffix(".rrd"))
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    read = [Trajectory.load(f) for f in sorted((run / "from_video").glob("*.npz"))]
    assert len(read) == 3 and all(t.meta["portal_from"] == "video" and t.portal.shape[1] == 5 for t in read)
    assert (run / estimator_name(load_spec(NO_EXPERT, AT_64))).is_file()  # kept with the run that used it
    widened = load_spec(run / "learned" / "spec.yaml").task.cue.centring_deg
    assert widened == VIDEO_CENTRING * load_spec(NO_EXPERT).task.cue.centring_deg  # poses off video are coarser
    # later, on a machine without the cache: the run's own estimator reads new videos
    monkeypatch.setenv("FASTRL_CACHE", str(tmp_path / "empty-cache"))
    new = tmp_path / "new.json"
    res = CliRunner().invoke(
        app, ["score", "--run", str(run / "learned"), str(folder / "L1-S01.mp4"), "-o", str(new), "--no-pictures"]
    )
    assert res.exit_code == 0, res.output
    assert json.loads(new.read_text())["trajectories"][0]["reward"] is not None
    assert not (tmp_path / "empty-cache").exists()


def test_a_new_estimator_learns_from_frames_rendered_as_the_videos_were(videos, tmp_path, monkeypatch):
    folder, _ = videos
    monkeypatch.setenv("FASTRL_CACHE", str(tmp_path / "cache"))
    learned_under, train = [], video_poses.train_estimator

    def small(env, progress=None):
        """The real training, on a tiny budget; notes the cue the frames were rendered under."""
        learned_under.append(env.unwrapped.task_spec.task.cue.centring_deg)
        return train(env, episodes=2, epochs=1, progress=progress)

    monkeypatch.setattr(video_poses, "train_estimator", small)
    res = CliRunner().invoke(
        app,
        ["assess", str(folder / "L1-S01.mp4"), str(folder / "L3-S01.mp4"), "--spec", str(NO_EXPERT), "--set", AT_64[0]]
        + ["--top", "1", "-o", str(tmp_path / "scores.json"), "--runs", str(tmp_path), "--no-progress"],
    )
    assert res.exit_code == 0, res.output
    # the videos' own cue (a wider one colours the avatars green on other views), while the replay widens it
    assert learned_under == [load_spec(NO_EXPERT).task.cue.centring_deg]
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    assert load_spec(run / "learned" / "spec.yaml").task.cue.centring_deg == VIDEO_CENTRING * learned_under[0]
