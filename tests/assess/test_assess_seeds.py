"""`fastrl assess --seeds N`: learned scores as mean and spread over seeds, their agreement, and the warnings."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from fastrl.assess.agreement import SEEDS_AGREE, combine
from fastrl.cli import app
from fastrl.data import Trajectory
from fastrl.data.cohort import make_cohort
from fastrl.spec import load_spec

from ..runner.test_runner import rrd_verify
from ..runner.test_stops import verify

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

NO_EXPERT = Path(__file__).parents[1] / "fixtures" / "no_expert.yaml"
LEVELS = np.repeat([1, 2, 3, 4, 5], 4)


def report(reward: np.ndarray, value: np.ndarray, time: np.ndarray) -> dict:
    """A per-seed report of 20 labelled files, as `fastrl score` writes it (normalised and raw learned scores)."""
    rows = [
        {
            "file": f"f{i:02d}",
            "subject": f"f{i:02d}",
            "skill": int(LEVELS[i]),
            "reward": float(r) / 10,
            "reward_raw": float(r),
            "value": float(v),
            "value_raw": float(v),
            "time": float(t),
            "path_length": 0.1 + float(t) / 100,
            "subtasks": 1.0,
        }
        for i, (r, v, t) in enumerate(zip(reward, value, time))
    ]
    keys = ["reward", "value", "time", "path_length", "subtasks"]
    return {"trajectories": rows, "scores": keys, "warnings": [], "grouped_by": "skill", "ranking": {}}


def test_agreeing_seeds_give_mean_spread_and_no_warning():
    rng = np.random.default_rng(0)
    skill = LEVELS + rng.normal(0, 0.3, 20)
    time = 30 - 5 * skill
    seeds = [report(3 * skill + rng.normal(0, 0.2, 20), skill + 10 * k, time) for k in range(3)]
    out = combine(seeds, [0, 1, 2])
    assert out["seeds"]["agreement"]["reward"]["mean_tau"] > 0.9
    assert out["seeds"]["with_simple_metrics"]["value"]["time"] > 0.9  # faster is better: it agrees with the clock
    assert not [w for w in out["warnings"] if "seeds disagree" in w or "against every" in w]
    row = out["trajectories"][0]
    values = [s["trajectories"][0]["value"] for s in seeds]
    assert row["value"] == pytest.approx(np.mean(values)) and row["value_sd"] == pytest.approx(np.std(values))
    assert out["ranking"]["reward"]["kendall_tau_b"] > 0.8


def test_seeds_that_disagree_by_construction_are_warned_of():
    rng = np.random.default_rng(1)
    time = 30 - 5 * LEVELS + rng.normal(0, 0.5, 20)
    orders = [rng.permutation(20).astype(float) for _ in range(3)]  # three unrelated rankings
    out = combine([report(o, LEVELS.astype(float), time) for o in orders], [0, 1, 2])
    assert out["seeds"]["agreement"]["reward"]["mean_tau"] < SEEDS_AGREE
    assert any(w.startswith("reward: the 3 seeds disagree") for w in out["warnings"])
    assert not any(w.startswith("value: the 3 seeds disagree") for w in out["warnings"])


def test_a_learned_score_against_every_simple_metric_is_warned_of():
    time = 30 - 5 * LEVELS + np.linspace(0, 0.5, 20)
    backwards = -LEVELS.astype(float) + np.linspace(0, 0.1, 20)  # the slowest scored best
    out = combine([report(backwards, backwards, time), report(backwards, backwards, time)], [3, 4])
    assert out["seeds"]["with_simple_metrics"]["reward"]["time"] < 0
    assert any(w.startswith("reward: ranks against every simple metric") for w in out["warnings"])


def test_a_learned_score_that_ranks_unlike_the_motion_is_warned_of():
    rng = np.random.default_rng(2)
    time = 30 - 5 * LEVELS + rng.normal(0, 0.5, 20)
    shuffled = rng.permutation(20).astype(float)  # a reward unrelated to how the trainees move
    seeds = []
    for _ in range(2):
        one = report(shuffled + rng.normal(0, 0.01, 20), LEVELS + rng.normal(0, 0.1, 20), time)
        for row, m in zip(one["trajectories"], LEVELS * 10.0):
            row["motion"] = m
        seeds.append({**one, "scores": [*one["scores"], "motion"], "warnings": ["reward: ranks unlike the motion (0)"]})
    out = combine(seeds, [0, 1])
    unlike = [w for w in out["warnings"] if "ranks unlike the motion" in w]
    assert len(unlike) == 1 and unlike[0].startswith("reward: ranks unlike the motion (Kendall tau")  # seed 0's dropped
    assert out["seeds"]["agreement"]["motion"]["mean_tau"] == pytest.approx(1.0)


@pytest.fixture(scope="module")
def cohort(tmp_path_factory):
    """A small cohort of the test task without actions."""
    folder = tmp_path_factory.mktemp("cohort")
    for traj in make_cohort(load_spec(NO_EXPERT), 3, 2, seed=0):
        Trajectory(traj.time, traj.portal, traj.meta).save(folder / f"{traj.meta['subject']}.npz")
    return folder


def assess_two_seeds(cohort: Path, folder: Path, *more: str):
    """`fastrl assess COHORT --seeds 2` into `folder` (runs and report), as on one core (the seeds one after
    another); (CLI result, report path)."""
    out = folder / "report" / "scores.json"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(os, "cpu_count", lambda: 1)
        res = CliRunner().invoke(
            app,
            ["assess", str(cohort), "--spec", str(NO_EXPERT), "--top", "2", "--seeds", "2", "-o", str(out)]
            + ["--runs", str(folder), "--no-progress", *more],
        )
    return res, out


@pytest.fixture(scope="module")
def two_seeds(tmp_path_factory, cohort):
    """The cohort assessed with two seeds, one after another: (CLI result, report path, runs folder)."""
    folder = tmp_path_factory.mktemp("two-seeds")
    return (*assess_two_seeds(cohort, folder), folder)


def same_scores(out: Path, serial: Path) -> None:
    """The two reports score every trajectory alike: the same networks were learned."""
    rows, serial_rows = (json.loads(p.read_text())["trajectories"] for p in (out, serial))
    for key in ("reward_raw", "value_raw", "reward_sd", "value_sd", "time"):
        assert [r[key] for r in rows] == pytest.approx([r[key] for r in serial_rows], rel=1e-9), key


def test_assess_with_two_seeds_learns_two_scorers_and_reports_their_agreement(two_seeds, cohort):
    res, out, tmp_path = two_seeds
    assert res.exit_code == 0, res.output
    assert "learned scores over seeds 0, 1: Kendall tau" in res.output
    assert "not necessarily a right one" in " ".join(res.output.split())  # agreement is not validity
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    assert (run / "learned-s0" / "networks").is_dir() and (run / "learned-s1" / "networks").is_dir()
    assert [load_spec(run / f"learned-s{s}" / "spec.yaml").train.seed for s in (0, 1)] == [0, 1]
    report = json.loads(out.read_text())
    assert report["seeds"]["seeds"] == [0, 1] and set(report["seeds"]["agreement"]) == {"reward", "value", "motion"}
    assert all(r["reward_sd"] is not None and r["value_sd"] >= 0 for r in report["trajectories"])
    for seed in (0, 1):  # each seed's own report is kept
        assert len(json.loads((out.parent / "seeds" / f"s{seed}" / "scores.json").read_text())["trajectories"]) == 6
    assert {"time", "path_length", "reward", "value"} <= set(report["ranking"])
    rrd_verify(out.with_suffix(".rrd"))
    assert out.with_name("scores_distributions.png").stat().st_size > 0
    bad = CliRunner().invoke(app, ["assess", str(cohort), "--spec", str(NO_EXPERT), "--seeds", "0"])
    assert bad.exit_code == 2 and "--seeds must be at least 1" in bad.output


def test_seeds_learned_at_once_on_ray_score_as_one_after_another(tmp_path, cohort, two_seeds):
    pytest.importorskip("ray")  # on loopback only: tests/conftest.py sets RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0
    res, out = assess_two_seeds(cohort, tmp_path, "--address", "local")
    assert res.exit_code == 0, res.output
    assert "learning 2 seeds on Ray (local), 0.5 CPU each" in res.output
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    assert load_spec(run / "learned-s1" / "spec.yaml").train.workers == 1  # each on its one CPU
    same_scores(out, two_seeds[1])


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="seeds learn at once only on spare cores")
def test_seeds_learned_at_once_on_spare_cores_score_as_one_after_another(tmp_path, cohort, two_seeds):
    out = tmp_path / "report" / "scores.json"
    res = subprocess.run(  # a fresh command's process (this one may have rendered: then they learn one by one)
        [sys.executable, "-m", "fastrl.cli", "assess", str(cohort), "--spec", str(NO_EXPERT), "--top", "2"]
        + ["--seeds", "2", "-o", str(out), "--runs", str(tmp_path), "--no-progress"],
        env={**os.environ, "CI": "1", "MUJOCO_GL": "egl"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr
    assert "learning 2 seeds, 2 at once, each in its own process" in res.stderr
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    assert [load_spec(run / f"learned-s{s}" / "spec.yaml").train.workers for s in (0, 1)] == [1, 1]
    verify(*(run / f"learned-s{s}" / "recording.rrd" for s in (0, 1)))  # each process closed its recording
    same_scores(out, two_seeds[1])


def wait_for_checkpoints(proc: subprocess.Popen, runs: Path, seeds: int = 2) -> None:
    """Until each seed of the assessment running in `proc` (into `runs`) has saved a checkpoint."""
    t0 = time.time()
    while len(list(runs.glob("medial_pair/*/learned-s*/checkpoints/[0-9]*/state.json"))) < seeds:
        assert proc.poll() is None, proc.communicate()
        assert time.time() - t0 < 180, "no checkpoint of every seed"
        time.sleep(0.2)


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="seeds learn at once only on spare cores")
@pytest.mark.parametrize(
    ("sig", "group"), [(signal.SIGINT, False), (signal.SIGTERM, False), (signal.SIGINT, True)]
)  # to the command alone (it stops its seeds' processes), or to them all as a terminal's Ctrl-C
def test_a_stop_while_seeds_learn_at_once_leaves_each_a_checkpoint_and_recording(tmp_path, cohort, sig, group):
    proc = subprocess.Popen(
        [sys.executable, "-m", "fastrl.cli", "assess", str(cohort), "--spec", str(NO_EXPERT), "--top", "2"]
        + ["--seeds", "2", "--runs", str(tmp_path), "--no-progress", "--set", "train.timesteps=400000"]
        + ["--set", "train.checkpoint_every=1024", "--set", "irl.generator.min_steps=400000"],
        env={**os.environ, "CI": "1", "MUJOCO_GL": "egl"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        start_new_session=True,
    )
    wait_for_checkpoints(proc, tmp_path)
    if group:
        os.killpg(proc.pid, sig)
    else:
        proc.send_signal(sig)
    _, err = proc.communicate(timeout=180)
    assert proc.returncode == 128 + sig and "Traceback" not in err, err
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    assert err.splitlines()[-1] == f"resume with: fastrl assess --resume {run}", err
    verify(*(run / f"learned-s{s}" / "recording.rrd" for s in (0, 1)))
    for seed in (0, 1):
        meta = json.loads((run / f"learned-s{seed}" / "meta.json").read_text())
        assert meta["status"] == "interrupted", meta
