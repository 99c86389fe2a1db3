"""Scoring trajectories: kinematic scores, ranking statistics, replay scores and `fastrl score` end to end."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from fastrl.agents.expert import ScriptedExpert
from fastrl.assess.kinematic import deviation_by_progress, log_dimensionless_jerk, path_length
from fastrl.assess.ranking import _boot_kendall, _scipy_stats, _spearman, _stats, rank_correlations
from fastrl.assess.references import compute_expert_paths, expert_paths, reference_scores
from fastrl.assess.report import build_report, score_files
from fastrl.assess.scoring import Scorer, held_to_limit, normalise, subtasks_reached
from fastrl.cli import app
from fastrl.data.replay import expert_trajectories, replay, rollout_trajectory
from fastrl.data.trajectory import Trajectory
from fastrl.irl.networks import load_networks
from fastrl.runner.score.assessment import assess
from fastrl.runner.score.helper import Helper
from fastrl.spec import load_spec

from ..conftest import spec_file
from ..runner.test_irl_runner import sets
from ..runner.test_runner import only_run, recorded, rrd_verify

SHORT = ["episode.time_limit=8"]


def _spec(name="tracelines", extra=()):
    return load_spec(spec_file(name), overrides=[*SHORT, *extra])


def degraded(scorer, seed: int, noise: float, level: int):
    """The scripted expert with a share `noise` of its actions replaced by random ones."""
    env, rng = scorer.env, np.random.default_rng(seed)
    expert = ScriptedExpert(env)
    env.action_space.seed(seed)

    def act(obs):
        return env.action_space.sample() if rng.random() < noise else expert.act(obs)

    meta = {"source": "synthetic", "subject": f"L{level}-{seed}", "skill": level}
    return rollout_trajectory(env, act, seed, meta, expert.reset)[0]


# --- pure scores ------------------------------------------------------------------------------


def test_path_length_of_a_known_polyline():
    tip = np.array([[0, 0, 0], [3, 4, 0], [3, 4, 12]], float)
    assert path_length(tip) == pytest.approx(5 + 12)


def test_smoothness_prefers_a_minimum_jerk_reach_over_a_shaky_one():
    t = np.linspace(0, 2, 201)
    s = t / 2
    smooth = np.stack([0.1 * (10 * s**3 - 15 * s**4 + 6 * s**5), np.zeros_like(t), np.zeros_like(t)], axis=1)
    shaky = smooth + 0.0005 * np.sin(2 * np.pi * 8 * t)[:, None] * [0, 1, 0]
    assert log_dimensionless_jerk(smooth, t) > log_dimensionless_jerk(shaky, t) + 1.0
    assert np.isnan(log_dimensionless_jerk(np.zeros((10, 3)), np.arange(10.0)))


def test_deviation_is_zero_against_itself_and_the_offset_otherwise():
    t = np.linspace(0, 3, 50)
    path = np.stack([t, t**2, 0 * t], axis=1)
    assert np.allclose(deviation_by_progress(path, t, path, t), 0)
    slower = deviation_by_progress(path + [0, 0, 0.01], t * 2, path, t)
    assert slower.shape == (101,) and np.allclose(slower, 0.01)


# --- ranking statistics on hand-made scores ---------------------------------------------------


def test_ranking_of_perfectly_ordered_levels():
    labels = np.repeat([1, 2, 3, 4, 5], 4)
    scores = labels * 10.0 + np.tile([0, 1, 2, 3], 5)
    r = rank_correlations(scores, labels, n_boot=200)
    assert r["levels_in_order"] and r["kendall_tau_b_of_level_means"] == pytest.approx(1.0)
    # tau-b with tied labels: every pair across levels is concordant, pairs within a level are ties
    assert r["kendall_tau_b"] == pytest.approx(np.sqrt(160 / 190), abs=1e-9)
    lo, hi = r["kendall_ci"]
    assert lo <= r["kendall_tau_b"] <= hi
    assert r["spearman"] > 0.9 and r["spearman_p"] < 1e-6


def test_ranking_detects_a_reversed_and_a_swapped_level():
    labels = np.repeat([1, 2, 3], 5)
    assert rank_correlations(-labels + 0.01 * np.arange(15), labels, n_boot=50)["kendall_tau_b"] < -0.8
    swapped = np.where(labels == 2, 3.5, labels).astype(float) + 0.01 * np.arange(15)
    r = rank_correlations(swapped, labels, n_boot=50)
    assert not r["levels_in_order"] and r["level_means"][2] > r["level_means"][3]


def test_ranking_of_constant_scores_is_undefined_not_a_crash():
    r = rank_correlations(np.ones(6), [1, 1, 2, 2, 3, 3], n_boot=20)
    assert r["kendall_tau_b"] is None and r["spearman"] is None and not r["levels_in_order"]


def test_statistics_and_p_values_equal_scipy_bit_for_bit():
    rng = np.random.default_rng(3)
    cases = [(rng.normal(size=n), rng.integers(1, 6, n).astype(float)) for n in (3, 8, 40, 100)]
    cases += [(rng.integers(0, 4, 50).astype(float), rng.integers(1, 3, 50).astype(float))]  # ties on both sides
    cases += [(np.ones(9), np.arange(9.0)), (np.arange(40.0), np.arange(40.0)), (rng.normal(size=50), -np.arange(50.0))]
    for x, y in cases:
        want, got = np.array(_scipy_stats(x, y), float), np.array(_stats(x, y), float)
        np.testing.assert_array_equal(got, want)


def test_batched_bootstrap_equals_scipy_on_every_resample_bit_for_bit():
    rng = np.random.default_rng(7)
    for n, tied in ((12, False), (30, True), (5, True)):
        x = rng.integers(0, 3, n).astype(float) if tied else rng.normal(size=n)
        y = rng.integers(1, 4, n).astype(float)
        draws = rng.integers(0, n, (40, n))
        draws[0] = 0  # a constant resample: both statistics undefined
        want = np.array([_scipy_stats(x[i], y[i])[::2] for i in draws], float)
        got = np.stack([_spearman(x[draws], y[draws]), _boot_kendall(x, y, draws)], axis=1)
        assert np.isnan(got[0]).all()
        np.testing.assert_array_equal(got, want)  # NaN where scipy's is, the same bits elsewhere


# --- replay scores ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def scorer():
    return Scorer(_spec())


def test_expert_outscores_a_noisy_expert_and_references_normalise_to_0_and_1(scorer):
    expert = expert_trajectories(scorer.env, [3])[0]
    noisy = degraded(scorer, 3, 0.6, 1)
    e, n = scorer.score(expert), scorer.score(noisy)
    assert e.scores["heuristic"] > n.scores["heuristic"]
    assert e.scores["subtasks"] > n.scores["subtasks"] and e.scores["time"] < n.scores["time"]
    assert e.scores["reward"] is None and e.values is None  # no learned model without a run
    refs = reference_scores(scorer, episodes=1)
    assert refs["expert"]["subtasks"] == 1.0 and refs["random"]["heuristic"] < refs["expert"]["heuristic"]
    ref_expert = scorer.score(expert_trajectories(scorer.env, [90000])[0])
    normalise([ref_expert], refs)
    assert ref_expert.normalised["heuristic"] == pytest.approx(1.0)


def test_expert_paths_from_the_cache_are_the_computed_ones(scorer, tmp_path):
    cache = tmp_path / "expert_paths.npz"
    first = expert_paths(scorer, [4, 2], cache)
    assert sorted(first) == [2, 4] and cache.exists()
    again = expert_paths(scorer, [2, 4, 6], cache)  # 2 and 4 read back, 6 computed and added
    for seed in (2, 4):
        np.testing.assert_array_equal(again[seed][0], first[seed][0])
        np.testing.assert_array_equal(again[seed][1], first[seed][1])
    fresh = expert_paths(scorer, [6])[6]
    np.testing.assert_array_equal(again[6][1], fresh[1])
    other = Scorer(_spec(extra=["episode.time_limit=9"]))  # another spec never reads this one's paths
    expert_paths(other, [2], cache)
    with np.load(cache) as z:
        assert sorted(z.files) == ["spec_hash", "time_2", "tip_2"]


def test_bad_and_foreign_files_are_reported_and_the_rest_scored(scorer, tmp_path):
    good = expert_trajectories(scorer.env, [0])[0]
    good.save(tmp_path / "good.npz")
    other = Scorer(_spec("imagecentring"))
    expert_trajectories(other.env, [0])[0].save(tmp_path / "other_task.npz")
    (tmp_path / "garbage.npz").write_bytes(b"not an archive")
    portal = good.portal.copy()
    portal[3] = np.nan
    np.savez(tmp_path / "nan_rows.npz", time=good.time, portal=portal, meta=json.dumps(good.meta))
    np.savez(tmp_path / "wrong_shape.npz", time=good.time, portal=good.portal[:, :4], meta=json.dumps(good.meta))
    files = sorted(tmp_path.glob("*.npz"))
    scored, problems = score_files(scorer, files)
    assert [s.name for s in scored] == ["good"]
    assert len(problems) == 4
    for name in ("other_task", "garbage", "nan_rows", "wrong_shape"):
        assert any(f"{name}.npz" in p for p in problems), (name, problems)
    assert any("another task" in p for p in problems)


def test_a_recording_scores_the_same_from_another_clock_start_and_at_a_rate_on_the_control_grid(scorer):
    traj = degraded(scorer, 6, 0.2, 3)
    t, p = traj.time, traj.portal
    fine = np.arange(0.0, t[-1] + 1e-9, 1.0 / 60.0)  # 60 Hz: every third sample on the 20 Hz grid
    portal = np.stack([np.interp(fine, t, p[:, j]) for j in range(5)], axis=1)
    base = scorer.score(traj)
    for other in (Trajectory(t + 1234.5, p, traj.meta), Trajectory(fine + 7.25, portal, traj.meta)):
        again = scorer.score(other)
        for k in ("heuristic", "subtasks", "time", "path_length"):
            assert again.scores[k] == pytest.approx(base.scores[k], rel=1e-6, abs=1e-9), k
    assert 0.0 < base.scores["subtasks"] < 1.0 or base.scores["time"] < 8.0  # a recording with something to lose


def test_report_groups_by_level_and_ranks_levels(scorer):
    trajs = [degraded(scorer, s, noise, level) for level, noise in ((3, 0.0), (2, 0.3), (1, 0.8)) for s in (5,)]
    scored = [scorer.score(t, f"t{i}") for i, t in enumerate(trajs)]
    references = {"random": {"heuristic": -100.0}, "expert": {"heuristic": 100.0}}
    normalise(scored, references)
    assert scored[0].normalised["heuristic"] == pytest.approx((scored[0].scores["heuristic"] + 100) / 200)
    report = build_report(scored, references, [], learned=False)
    assert report["grouped_by"] == "skill"
    assert [g["subject"] for g in report["groups"]][0] == "level 3"
    assert set(report["ranking"]) == {"heuristic", "subtasks", "path_length", "time", "smoothness"}
    assert report["ranking"]["time"]["kendall_tau_b"] > 0.5


# --- end to end ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def airl_run(tmp_path_factory):
    runs = tmp_path_factory.mktemp("runs")
    res = CliRunner().invoke(
        app,
        [
            "irl",
            str(spec_file("tracelines")),
            "--algorithm",
            "airl",
            "--timesteps",
            "256",
            *sets(),
            "--runs",
            str(runs),
            "--no-progress",
        ],
    )
    assert res.exit_code == 0, res.output
    return only_run(runs)


def test_fastrl_score_with_a_run_writes_json_csv_figures_and_a_valid_recording(airl_run, tmp_path):
    spec = load_spec(airl_run / "spec.yaml")
    scorer = Scorer(spec)
    for level, noise in ((2, 0.0), (1, 0.7)):
        for s in (1, 2):
            degraded(scorer, s, noise, level).save(tmp_path / "in" / f"L{level}_{s}.npz")
    (tmp_path / "in" / "broken.npz").write_bytes(b"\x00" * 10)
    out = tmp_path / "out" / "scores.json"
    res = CliRunner().invoke(
        app,
        ["score", "--run", str(airl_run), str(tmp_path / "in"), "-o", str(out), "--references", "1", "--no-progress"],
    )
    assert res.exit_code == 0, res.output
    assert "broken.npz" in res.output and "scored 4 trajectories" in res.output
    report = json.loads(out.read_text())
    assert len(report["trajectories"]) == 4 and len(report["problems"]) == 1
    row = report["trajectories"][0]
    assert row["reward"] is not None and row["value"] is not None and np.isfinite(row["reward_raw"])
    assert {"reward", "value", "potential", "heuristic"} <= set(report["ranking"])
    nets = load_networks(airl_run / "networks")  # AIRL's value by its shaping potential: mean h over the states
    obs, _, _ = replay(scorer.env, Trajectory.load(tmp_path / "in" / f"{row['file']}.npz"))
    assert row["potential_raw"] == pytest.approx(float(nets.potential(obs).mean()), rel=1e-5)
    csv_lines = out.with_suffix(".csv").read_text().splitlines()
    assert len(csv_lines) == 5 and csv_lines[0].startswith("file,subject,skill")
    for png in ("scores_paths.png", "scores_deviation.png", "scores_distributions.png"):
        assert (out.parent / png).stat().st_size > 10_000
    rrd = out.with_suffix(".rrd")
    rrd_verify(rrd)
    entities, _ = recorded(rrd)
    assert any(e.startswith("/world/assessment/") for e in entities)
    assert any(e.startswith("/assessment/deviation/") for e in entities)
    assert (airl_run / "assessment" / "references.json").exists()  # cached for the next scoring


def test_scoring_in_two_processes_gives_the_same_report_in_the_same_order(scorer, tmp_path):
    for i, (level, noise) in enumerate(((2, 0.0), (1, 0.7), (2, 0.1), (1, 0.5))):
        degraded(scorer, 10 + i, noise, level).save(tmp_path / "in" / f"t{i}.npz")
    (tmp_path / "in" / "t1b.npz").write_bytes(b"broken")  # a problem between the two halves keeps its place
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(scorer.spec.model_dump(mode="json")))
    reports = []
    for parallel in (False, True):
        out = tmp_path / f"out-{parallel}" / "scores.json"
        result = assess(
            [tmp_path / "in"],
            spec_path=spec,
            output=out,
            reference_episodes=1,
            progress=False,
            parallel=parallel,
        )
        assert {"paths", "deviation", "distributions", "rrd"} <= set(result.files)
        reports.append({k: v for k, v in json.loads(out.read_text()).items() if k != "seconds"})
    assert reports[0] == reports[1] and [r["file"] for r in reports[1]["trajectories"]] == ["t0", "t1", "t2", "t3"]
    assert len(reports[1]["problems"]) == 1 and "t1b.npz" in reports[1]["problems"][0]


def test_a_run_scored_in_two_processes_gives_the_same_report_and_neither_process_imports_torch(airl_run, tmp_path):
    scorer = Scorer(load_spec(airl_run / "spec.yaml"))
    for i, (level, noise) in enumerate(((2, 0.0), (1, 0.7), (2, 0.2))):
        degraded(scorer, 20 + i, noise, level).save(tmp_path / "in" / f"t{i}.npz")
    here = tmp_path / "here" / "scores.json"
    assess([tmp_path / "in"], run=airl_run, output=here, reference_episodes=1, pictures=False, parallel=False)
    two = tmp_path / "two" / "scores.json"
    script = (  # the whole command in a fresh interpreter (this one has torch already), forced to use the helper
        "import sys; from fastrl.runner.score import helper; helper.MIN_FILES = 2; from fastrl.cli import app; "
        "app(sys.argv[1:])"
    )
    args = ["score", str(tmp_path / "in"), "--run", str(airl_run), "-o", str(two), "--references", "1"]
    res = subprocess.run(  # -X importtime: every module imported, by this process and the forked helper alike
        [sys.executable, "-X", "importtime", "-c", script, *args, "--no-progress"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    imported = {line.split("|")[-1].strip() for line in res.stderr.splitlines() if line.startswith("import time:")}
    assert "safetensors.numpy" in imported  # the networks were loaded
    assert not {"torch", "stable_baselines3", "ray"} & imported  # numpy evaluates the networks
    reports = [{k: v for k, v in json.loads(p.read_text()).items() if k != "seconds"} for p in (here, two)]
    assert reports[0] == reports[1]  # bit for bit: each trajectory's networks evaluated alone, in either process
    assert all(r["reward_raw"] is not None and r["value_raw"] is not None for r in reports[1]["trajectories"])
    assert (two.parent / "scores_paths.png").stat().st_size > 10_000 and two.with_suffix(".rrd").exists()


def test_fastrl_imported_after_numpy_still_holds_blas_to_one_thread():
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}  # as a fresh shell has it
    script = "import json, numpy, fastrl, threadpoolctl; print(json.dumps(threadpoolctl.threadpool_info()))"
    res = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=120)
    blas = [lib["num_threads"] for lib in json.loads(res.stdout) if lib["user_api"] == "blas"]
    assert blas and set(blas) == {1}, res.stdout + res.stderr


def test_expert_paths_from_the_helper_process_are_the_ones_computed_here(scorer):
    helper = Helper(scorer)
    try:
        shared = helper.expert_paths([7, 8, 9])  # 7 in the worker, 8 and 9 here
    finally:
        helper.close()
    for seed, (t, tip) in compute_expert_paths(scorer, [7, 8, 9]).items():
        np.testing.assert_array_equal(shared[seed][0], t)
        np.testing.assert_array_equal(shared[seed][1], tip)


def test_fastrl_score_needs_a_run_or_a_spec(tmp_path):
    res = CliRunner().invoke(app, ["score", str(tmp_path)])
    assert res.exit_code == 2 and "--run RUN_DIR, or --spec SPEC" in res.output
    res = CliRunner().invoke(
        app,
        [
            "score",
            "--spec",
            str(spec_file("tracelines")),
            str(tmp_path / "none.npz"),
            "-o",
            str(tmp_path / "s.json"),
            "--no-progress",
            "--references",
            "1",
        ],
    )
    assert res.exit_code == 2 and "no trajectory could be scored" in res.output


def test_a_trajectory_that_succeeds_while_held_still_is_said_to_be_held_only_that_long():
    spec = _spec()
    scorer = Scorer(spec)
    full = expert_trajectories(scorer.env, [0])[0]
    cut = Trajectory(full.time[:-1], full.portal[:-1], full.meta)  # one sample short of the final dwell
    scored = scorer.score(cut)
    assert scored.meta["success"] and scored.scores["time"] == pytest.approx(full.time[-1] - full.time[0])
    assert scored.meta["held_still_s"] == pytest.approx(1 / spec.episode.control_hz)


def test_a_trajectory_that_stops_early_is_scored_as_held_still_to_the_time_limit():
    spec = _spec()
    scorer = Scorer(spec)
    full = expert_trajectories(scorer.env, [0])[0]
    n = len(full.time) // 3
    cut = Trajectory(full.time[:n], full.portal[:n], full.meta)
    whole, stopped = scorer.score(full), scorer.score(cut)
    assert "held_still_s" not in whole.meta and whole.scores["time"] < spec.episode.time_limit
    assert stopped.scores["time"] == pytest.approx(spec.episode.time_limit)
    assert stopped.meta["held_still_s"] == pytest.approx(spec.episode.time_limit - cut.time[-1] + cut.time[0])
    assert stopped.scores["path_length"] == pytest.approx(path_length(stopped.tip[:n]))  # held: no more path
    assert stopped.scores["heuristic"] < whole.scores["heuristic"] and not stopped.meta["success"]
    _, infos, _ = replay(scorer.env, cut)  # scored in one pass: the same as the cut replayed, then held and replayed
    _, _, rewards = replay(scorer.env, held_to_limit(cut, spec, len(infos)))
    assert not infos[-1]["success"] and stopped.scores["heuristic"] == pytest.approx(rewards.sum(), abs=1e-12)


def test_a_trainee_who_stops_early_pays_the_learned_cost_of_each_subtask_reached(airl_run):
    scorer = Scorer(load_spec(airl_run / "spec.yaml"))
    scorer.attach(load_networks(airl_run / "networks"))
    full = expert_trajectories(scorer.env, [0])[0]
    n = len(full.time) // 3
    whole, stopped = scorer.score(full), scorer.score(Trajectory(full.time[:n], full.portal[:n], full.meta))
    total, done = stopped.meta["subtasks_total"], stopped.meta["subtasks_done"]
    assert whole.meta["subtasks_done"] == total and 0 < done + 1 < total  # it stopped on a subtask it had reached
    assert subtasks_reached(whole.meta) == total and subtasks_reached(stopped.meta) == done + 1
    for scored, per in ((whole, total), (stopped, done + 1)):
        assert scored.scores["reward"] == pytest.approx(scored.rewards.sum() / per, rel=1e-9)
        assert scored.scores["value"] == pytest.approx(scored.values.sum() / per, rel=1e-9)
    assert subtasks_reached({"subtasks_done": 0, "subtasks_total": 0}) == 1  # a task without subtasks: the sum
