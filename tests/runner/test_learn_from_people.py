"""Learning from recordings without actions, and `fastrl assess` on a task that has no scripted expert."""

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from fastrl.agents.expert import ScriptedExpert
from fastrl.cli import app
from fastrl.data import Trajectory
from fastrl.data.cohort import make_cohort
from fastrl.data.inverse import ActionRecovery, agreement, on_control_grid, to_control_rate
from fastrl.data.poses import poses_from_portal
from fastrl.data.replay import expert_trajectories
from fastrl.env import FastEnv
from fastrl.spec import load_spec

from ..conftest import spec_file
from .test_irl_runner import SAC, sets
from .test_runner import only_run, rrd_verify

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

NO_EXPERT = Path(__file__).parents[1] / "fixtures" / "no_expert.yaml"
SHORT = ["episode.time_limit=8"]


@pytest.mark.parametrize("mode", ["discrete", "rates"])
def test_actions_recovered_from_states_match_the_true_ones(mode):
    spec = load_spec(spec_file("tracelines"), [*SHORT, f"actions.mode={mode}"])
    traj = expert_trajectories(FastEnv(spec), [3])[0]
    rec = ActionRecovery(FastEnv(spec)).recover(Trajectory(traj.time, traj.portal, traj.meta))
    assert rec.actions.shape == np.asarray(traj.actions).shape
    score = agreement(traj.actions, rec.actions, mode)
    if mode == "discrete":
        assert score["exact_match"] == 1.0 and rec.residual.max() < 1e-9
    else:
        assert score["mean_abs_error"] < 0.01 and rec.residual.mean() < 0.01
        assert np.abs(rec.actions).max() <= 1.0


def test_off_grid_recordings_are_resampled_onto_the_control_grid():
    spec = load_spec(spec_file("tracelines"), SHORT)
    traj = expert_trajectories(FastEnv(spec), [0])[0]
    fine_t = np.arange(0, traj.time[-1], 1 / 60)  # a 60 Hz tracker
    q = np.column_stack([np.interp(fine_t, traj.time, traj.portal[:, j]) for j in range(5)])
    fine = Trajectory(fine_t, q, {"seed": 0})
    assert not on_control_grid(fine, 20)
    back = to_control_rate(fine, 20)
    assert on_control_grid(back, 20) and back.actions is None and back.meta["resampled_from"] == len(fine_t)
    n = min(len(back.time), len(traj.time))
    assert np.abs(back.portal[:n] - traj.portal[:n]).max() < 1e-6  # linear between samples of a linear path
    assert to_control_rate(traj, 20) is traj


def test_resampling_carries_every_instrument_and_the_free_bodies():
    spec = load_spec(spec_file("loose_bodies"), SHORT)
    traj = expert_trajectories(FastEnv(spec), [0])[0]
    assert traj.instruments is not None and traj.bodies is not None
    fine_t = np.arange(0, traj.time[-1] + 1e-9, 1 / 60)  # a 60 Hz tracker: every third sample on the 20 Hz grid
    every = [np.interp(fine_t, traj.time, c) for c in traj.portal.T]
    tools = np.column_stack([np.interp(fine_t, traj.time, c) for c in traj.instruments.T])
    flat = traj.bodies.reshape(len(traj.time), -1)
    bodies = np.column_stack([np.interp(fine_t, traj.time, c) for c in flat.T]).reshape(len(fine_t), -1, 7)
    back = to_control_rate(
        Trajectory(fine_t, np.column_stack(every), {"seed": 0}, instruments=tools, bodies=bodies), 20
    )
    n = min(len(back.time), len(traj.time))
    np.testing.assert_allclose(back.instruments[:n], traj.instruments[:n], atol=1e-9)
    np.testing.assert_allclose(back.bodies[:n], traj.bodies[:n], atol=1e-9)
    mid = to_control_rate(traj, 40)  # halfway between two samples: quaternions stay unit
    np.testing.assert_allclose(np.linalg.norm(mid.bodies[..., 3:], axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(mid.instruments[1], traj.instruments[:2].mean(0), atol=1e-12)


def _demo_folder(tmp_path: Path, keep_actions: int) -> Path:
    """Three scripted-expert demonstrations; all but `keep_actions` of them lose their actions."""
    res = CliRunner().invoke(
        app,
        ["demos", "--expert", str(spec_file("tracelines")), "-n", "3", "-o", str(tmp_path / "demos"), "--no-progress"],
    )
    assert res.exit_code == 0, res.output
    for i, f in enumerate(sorted((tmp_path / "demos").glob("*.npz"))):
        if i >= keep_actions:
            t = Trajectory.load(f)
            Trajectory(t.time, t.portal, t.meta).save(f)
    return tmp_path / "demos"


@pytest.mark.parametrize(
    ("algorithm", "keep", "extra"),
    [("airl", 0, []), ("gail", 1, []), ("bc", 1, []), ("airl", 1, ["actions.mode=rates", *SAC[1:]])],
    ids=["airl-no-actions", "gail-mixed", "bc-mixed", "airl-sac-rates-mixed"],
)
def test_irl_learns_from_a_folder_without_actions(tmp_path, algorithm, keep, extra):
    demos = _demo_folder(tmp_path, keep)
    ranking = ["irl.discriminator.ranking_noise=[0, 1]", "irl.discriminator.ranking_episodes=1"]
    res = CliRunner().invoke(
        app,
        ["irl", str(spec_file("tracelines")), "--demos", str(demos), "--algorithm", algorithm, "--timesteps", "256"]
        + sets([*ranking, *extra])
        + ["--runs", str(tmp_path / "runs"), "--no-progress"],
    )
    assert res.exit_code == 0, res.output
    recovered = 3 if extra else 3 - keep  # discrete actions in a rates task are recovered as rates too
    assert f"recovered the actions of {recovered} of 3 demonstrations" in res.output
    assert "skipped" not in res.output
    run = only_run(tmp_path / "runs")
    assert json.loads((run / "meta.json").read_text())["status"] == "done"
    assert (run / "networks" / "policy.safetensors").exists()
    if algorithm == "airl" and not extra:  # the ranking prior came from a policy cloned from the recordings
        assert "irl/ranking_loss" in (run / "metrics.jsonl").read_text()


@pytest.fixture(scope="module")
def people(tmp_path_factory):
    """Recordings of the task without a scripted expert, as people bring them: a cohort without actions, a
    tracked-pose CSV import at 50 Hz, a file whose meta has nothing optional, a broken file, another task's file."""
    folder = tmp_path_factory.mktemp("people")
    spec = load_spec(NO_EXPERT)
    for traj in make_cohort(spec, 3, 3, seed=0):  # made before the expert goes away: they stand for people
        Trajectory(traj.time, traj.portal, traj.meta).save(folder / f"{traj.meta['subject']}.npz")
    best = Trajectory.load(folder / "L3-S01.npz")
    t50 = np.arange(0, best.time[-1], 0.02)
    q50 = np.column_stack([np.interp(t50, best.time, best.portal[:, j]) for j in range(5)])
    env = FastEnv(spec)
    rows = poses_from_portal(env.task, t50, q50)
    csv = folder.parent / "tracked.csv"
    csv.write_text("time,x,y,z,qw,qx,qy,qz,cable\n" + "\n".join(",".join(f"{v:.9g}" for v in r) for r in rows))
    res = CliRunner().invoke(
        app,
        ["import-poses", str(NO_EXPERT), str(csv), "-o", str(folder / "tracked.npz"), "--no-resample"]
        + ["--subject", "tracked", "--skill", "3", "--seed", str(best.meta["seed"])],
    )
    assert res.exit_code == 0, res.output
    bare = Trajectory.load(folder / "L2-S01.npz")
    np.savez(folder / "bare.npz", time=bare.time, portal=bare.portal, meta=np.array("{}"))
    (folder / "broken.npz").write_bytes(b"not a trajectory")
    other = expert_trajectories(FastEnv(load_spec(spec_file("tracelines"), SHORT)), [0])[0]
    other.save(folder / "other_task.npz")
    return folder


def test_assess_runs_the_protocol_on_a_task_without_a_scripted_expert(tmp_path, people, monkeypatch):
    def unavailable(*_a, **_k):
        raise RuntimeError("this task has no scripted expert")

    monkeypatch.setattr(ScriptedExpert, "__init__", unavailable)
    out = tmp_path / "report" / "scores.json"
    res = CliRunner().invoke(
        app,
        ["assess", str(people), "--spec", str(NO_EXPERT), "--top", "3", "-o", str(out), "--runs", str(tmp_path)]
        + ["--no-progress", "--set", "irl.generator.recorded_starts=0.5"],
    )
    assert res.exit_code == 0, res.output
    rule = "by subtasks completed (more first), then the sum of the ranks by duration and by the motion's likelihood"
    assert f"learned from the 3 best of 11 recordings {rule}" in res.output
    skipped = [line for line in res.output.splitlines() if line.startswith("skipped")]
    assert len(skipped) == 2 and any("broken.npz" in s for s in skipped) and any("other_task" in s for s in skipped)
    report = json.loads(out.read_text())
    assert len(report["trajectories"]) == 11
    assert {"heuristic", "reward", "value"} <= set(report["ranking"])
    assert "recordings the model learned from" in report["references"]["description"]
    for kind in ("csv", "paths", "deviation", "distributions"):
        assert out.with_name(f"scores{'' if kind == 'csv' else '_' + kind}.{'csv' if kind == 'csv' else 'png'}")
    rrd_verify(out.with_suffix(".rrd"))
    run = next(tmp_path.glob("medial_pair/*-assess-airl-s0"))
    protocol = json.loads((run / "protocol.json").read_text())
    assert len(protocol["chosen"]) == 3 and protocol["order"][0] in {c["file"] for c in protocol["chosen"]}
    best = [Trajectory.load(f) for f in sorted((run / "best").glob("*.npz"))]
    assert len(best) == 3 and all(t.actions is None for t in best)
    others = {f.stem for f in (run / "others").glob("*.npz")}  # the rest, as the generator's training starts
    assert len(others) == 8 and not others & {f.stem for f in (run / "best").glob("*.npz")}
    learned = run / "learned"
    assert "expert" not in json.loads((learned / "eval.json").read_text())
    assert "irl/ranking_loss" in (learned / "metrics.jsonl").read_text()
    # the learned networks score new trainees later, still without the scripted expert
    res = CliRunner().invoke(
        app, ["score", "--run", str(learned), str(people / "L1-S01.npz"), "-o", str(tmp_path / "new.json")]
    )
    assert res.exit_code == 0, res.output
    assert json.loads((tmp_path / "new.json").read_text())["trajectories"][0]["reward"] is not None


def test_assess_reports_bad_options_and_empty_cohorts_in_one_line(tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "broken.npz").write_bytes(b"nothing")
    for extra, message in (
        (["--by", "speed"], "--by must be one of motion, time, length, heuristic"),
        (["--algorithm", "bc"], "--algorithm must be one of airl, gail"),
        (["--top", "0"], "--top must be at least 1"),
        ([], "nothing to learn from; 1 skipped, the first: " + str(empty / "broken.npz")),
    ):
        res = CliRunner().invoke(app, ["assess", str(empty), "--spec", str(NO_EXPERT), "--runs", str(tmp_path), *extra])
        assert res.exit_code == 2 and message in res.output and "Traceback" not in res.output, res.output
    assert not list(tmp_path.glob("medial_pair/*"))  # nothing half-made
    nested = tmp_path / "course" / "cohort"
    nested.mkdir(parents=True)
    (nested / "L1-S01.npz").write_bytes(b"nothing")
    res = CliRunner().invoke(app, ["assess", str(nested.parent), "--spec", str(NO_EXPERT), "--runs", str(tmp_path)])
    message = f"no recording (.npz or video) in {nested.parent}: nothing to learn from; {nested} holds some"
    assert res.exit_code == 2 and message in " ".join(res.output.split()), res.output


def test_recorded_starts_without_recordings_are_refused_in_one_line(tmp_path):
    """A run asking its generator to start at recorded states, with the scripted expert's demonstrations and no
    recordings, stops before training with one line that says what to set."""
    args = ["run", str(spec_file("tracelines")), "--runs", str(tmp_path), "--no-progress"]
    args += ["--set", "irl.algorithm=airl", "--set", "irl.generator.recorded_starts=0.5"]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 2 and "Traceback" not in res.output, res.output
    assert "no recordings to start from: set irl.demonstrations.path" in " ".join(res.output.split())
