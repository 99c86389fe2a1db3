"""`fastrl assess --resume RUN`: a stopped assessment goes on where it stopped, with its own recordings and options."""

import json
import os
import shutil
import signal
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from fastrl.cli import app

from ..runner.test_stops import verify
from .test_assess_seeds import NO_EXPERT, cohort, wait_for_checkpoints  # noqa: F401  (cohort: the fixture)

pytestmark = pytest.mark.slow  # trains end to end

ENV = {**os.environ, "CI": "1", "MUJOCO_GL": "egl"}


def fastrl(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """A fresh `fastrl` command (its own process: the seeds learn at once on spare cores)."""
    return subprocess.run(
        [sys.executable, "-m", "fastrl.cli", *args], env=ENV, capture_output=True, text=True, timeout=timeout
    )


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="the stop lands while the seeds learn at once")
def test_a_stopped_assessment_resumes_each_seed_where_it_stopped_and_scores(tmp_path, cohort):  # noqa: F811
    budget = ["--set", "train.timesteps=30000", "--set", "irl.generator.min_steps=30000"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "fastrl.cli", "assess", str(cohort), "--spec", str(NO_EXPERT), "--top", "2"]
        + ["--seeds", "2", "--runs", str(tmp_path), "--no-progress", *budget, "--set", "train.checkpoint_every=1024"],
        env=ENV,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
    )
    wait_for_checkpoints(proc, tmp_path)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=180)
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    assert proc.returncode == 130 and err.splitlines()[-1] == f"resume with: fastrl assess --resume {run}", err
    assert not (run / "scores.json").exists()
    shutil.rmtree(run / "learned-s1")  # as a stop of seeds learned one after another leaves it: never begun

    stopped_at = max(int(c.name) for c in (run / "learned-s0" / "checkpoints").glob("[0-9]*"))

    res = fastrl("assess", "--resume", str(run), "--no-progress")
    assert res.returncode == 0, res.stderr
    assert f"learned-s0: resumes from {stopped_at} timesteps" in res.stderr, res.stderr
    assert "learned-s1: starts" in res.stderr, res.stderr
    for seed in (0, 1):
        meta = json.loads((run / f"learned-s{seed}" / "meta.json").read_text())
        assert meta["status"] == "done" and meta["trained_timesteps"] >= 30000, meta
    report = json.loads((run / "scores.json").read_text())
    assert report["seeds"]["seeds"] == [0, 1] and len(report["trajectories"]) == 6
    assert json.loads((run / "meta.json").read_text())["status"] == "done"
    verify(run / "learned-s0" / "recording.rrd", run / "learned-s1" / "recording.rrd", run / "scores.rrd")

    again = fastrl("assess", "--resume", str(run), "--no-progress")  # nothing left to learn: kept, scored again
    assert again.returncode == 0, again.stderr
    assert "learned-s0: learned, kept" in again.stderr and "learned-s1: learned, kept" in again.stderr
    assert json.loads((run / "scores.json").read_text())["trajectories"] == report["trajectories"]


def test_a_stop_while_scoring_keeps_the_learned_networks_and_resume_scores(tmp_path, cohort, monkeypatch):  # noqa: F811
    import fastrl.runner.protocol as protocol

    runner = CliRunner()
    args = ["assess", str(cohort), "--spec", str(NO_EXPERT), "--top", "2", "--runs", str(tmp_path), "--no-progress"]

    def stopped(*a, **k):
        raise KeyboardInterrupt

    with monkeypatch.context() as mp:
        mp.setattr(protocol, "assess", stopped)  # Ctrl-C once scoring began
        res = runner.invoke(app, args)
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    assert res.exit_code == 130, res.output
    assert f"scoring stopped; the learned networks are kept in {run}" in " ".join(res.output.split())
    assert res.output.splitlines()[-1] == f"resume with: fastrl assess --resume {run}"
    learned_at = (run / "learned" / "meta.json").stat().st_mtime_ns

    res = runner.invoke(app, ["assess", "--resume", str(run), "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "learned: learned, kept" in res.output
    assert (run / "learned" / "meta.json").stat().st_mtime_ns == learned_at  # not learned again
    assert len(json.loads((run / "scores.json").read_text())["trajectories"]) == 6


def test_resume_refuses_what_it_cannot_continue(tmp_path, cohort):  # noqa: F811
    runner = CliRunner()
    res = runner.invoke(app, ["assess"])
    assert res.exit_code == 2 and "or --resume RUN" in res.output
    res = runner.invoke(app, ["assess", "--resume", str(tmp_path), str(cohort)])
    assert res.exit_code == 2 and "give none" in res.output
    res = runner.invoke(app, ["assess", "--resume", str(tmp_path / "nowhere")])
    assert res.exit_code == 2 and "nowhere" in res.output and "Traceback" not in res.output
    train = runner.invoke(app, ["run", str(NO_EXPERT), "--runs", str(tmp_path), "--no-progress"])
    assert train.exit_code == 0, train.output
    trained = next(p.parent for p in tmp_path.glob("medial_pair/*/meta.json"))
    res = runner.invoke(app, ["assess", "--resume", str(trained)])
    assert res.exit_code == 2 and "was not made by fastrl assess" in res.output
