"""The motion's likelihood: a density of the recordings' steps that scores how like them, and how long, one moves."""

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from fastrl.assess.motion import FILE, MotionModel, motion_columns, step_motion, transition_motion
from fastrl.cli import app
from fastrl.data import Trajectory
from fastrl.data.cohort import make_cohort, with_overlays
from fastrl.env.fast_env import FastEnv
from fastrl.spec import load_spec

from ..conftest import spec_file

NO_EXPERT = Path(__file__).parents[1] / "fixtures" / "no_expert.yaml"


def moves(seed: int, seconds: float = 10.0, shake: float = 0.0, lag: float = 0.0) -> np.ndarray:
    """Steps of a hand reaching from target to target at 20 Hz (step_motion's columns), shaking or lagging."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, seconds, 0.05)
    speed = np.abs(np.sin(np.pi * t / 2)) * 0.03 + rng.normal(0, 0.001, len(t)) ** 2
    if lag:  # a sluggish hand: the same moves, low-pass filtered
        kernel = np.exp(-np.arange(0, 5 * lag, 0.05) / lag)
        speed = np.convolve(speed, kernel / kernel.sum())[: len(t)]
    speed = np.abs(speed + shake * rng.normal(0, 0.02, len(t)))
    turn = np.abs(10 * speed + rng.normal(0, 0.02, len(t)))  # turning as it moves, not in lockstep
    obs = np.column_stack([speed, np.zeros_like(t), np.zeros_like(t), turn, np.zeros((len(t), 3))])
    return step_motion(obs, ([0, 1, 2], [3, 4, 5, 6]))


def test_steps_read_speed_turn_rate_and_their_change():
    obs = np.array([[3.0, 4.0, 0.0, 1.0, 0.0], [0.0, 0.0, 1.0, 0.0, 2.0]])
    steps = step_motion(obs, ([0, 1, 2], [3, 4]))
    assert steps.tolist() == [[5.0, 1.0, 0.0, 0.0], [1.0, 2.0, 4.0, 1.0]]


def test_a_transition_reads_the_motion_of_its_arrival_as_the_step_there():
    obs = np.abs(np.random.default_rng(0).normal(size=(6, 7)))
    columns = ([0, 1, 2], [3, 4, 5, 6])
    assert np.array_equal(transition_motion(obs[:-1], obs[1:], columns), step_motion(obs, columns)[1:])


def test_no_recorded_step_lies_above_the_ceiling_and_the_reward_term_counts_down_from_it(tmp_path):
    recorded = [moves(seed) for seed in range(3)]
    model = MotionModel.fit(recorded)
    density = model.log_density(np.concatenate(recorded))
    assert density.max() == pytest.approx(model.ceiling)
    assert not model.reward(density).any()  # unweighed: no reward term
    weighed = model.weighing(2.0, 0.5)
    assert np.allclose(weighed.reward(density), 2.0 * (density - model.ceiling)) and weighed.reward(density).max() == 0
    shaking = weighed.reward(weighed.log_density(moves(10, shake=1.0)))
    assert shaking.mean() < weighed.reward(weighed.log_density(moves(10))).mean() - 1.0
    back = MotionModel.load(weighed.save(tmp_path / FILE))
    assert (back.ceiling, back.reward_weight, back.value_weight) == (model.ceiling, 2.0, 0.5)


def test_the_value_term_is_the_discounted_motion_still_to_come_from_each_state():
    model = MotionModel.fit([moves(seed) for seed in range(3)]).weighing(2.0, 0.5)
    density = model.log_density(moves(10, shake=1.0))
    value = model.value(density, 0.9)
    below = 0.5 * (density - model.ceiling)
    by_hand = [sum(0.9**k * b for k, b in enumerate(below[t:])) for t in range(len(below))]
    assert len(value) == len(density) + 1 and value[-1] == 0.0  # one per state; nothing to come after the last
    assert np.allclose(value[:-1], by_hand)
    steady = model.value(model.log_density(moves(10)), 0.9)
    assert value[0] < steady[0] < 0.0  # a shaking hand has more cost ahead than a steady one
    assert not MotionModel.fit([moves(0)]).value(density, 0.9).any()  # unweighed: no value term


def test_a_model_written_before_the_reward_term_reads_back_without_one(tmp_path):
    from safetensors.numpy import save_file

    model = MotionModel.fit([moves(0)])
    save_file({k: getattr(model, k) for k in ("reference", "floor", "mean", "spread")}, tmp_path / FILE)
    old = MotionModel.load(tmp_path / FILE)
    assert old.reward_weight == old.value_weight == 0.0
    assert old.log_likelihood(moves(1)) == model.log_likelihood(moves(1))


def test_a_shaking_sluggish_or_slower_hand_is_less_likely_than_the_recordings():
    model = MotionModel.fit([moves(seed) for seed in range(5)])
    like = model.log_likelihood(moves(10))
    assert model.log_likelihood(moves(10, shake=1.0)) < like - 50  # tremor
    assert model.log_likelihood(moves(10, lag=1.0)) < like - 50  # a sluggish hand, the same moves
    assert model.log_likelihood(moves(10, seconds=20.0)) < like - 50  # the same moves for twice as long


def test_recordings_whose_features_move_in_lockstep_still_give_a_density():
    steps = moves(0)
    steps[:, 1], steps[:, 3] = 10 * steps[:, 0], 10 * steps[:, 2]  # turn rate always ten times the speed
    assert np.isfinite(MotionModel.fit([steps]).log_likelihood(moves(1)))


def test_a_model_reads_back_as_written_and_a_torn_file_is_named(tmp_path):
    model = MotionModel.fit([moves(seed) for seed in range(3)])
    back = MotionModel.load(model.save(tmp_path / FILE))
    assert back.log_likelihood(moves(7)) == model.log_likelihood(moves(7))
    torn = tmp_path / "torn.safetensors"
    torn.write_bytes((tmp_path / FILE).read_bytes()[:100])
    with pytest.raises(ValueError, match="torn.safetensors: not a motion model"):
        MotionModel.load(torn)


def test_no_motion_score_without_camera_velocities_or_beside_instruments():
    assert motion_columns(load_spec(spec_file("liver_tour"))) is None
    assert motion_columns(load_spec(spec_file("triangulation"))) is None  # the hands move, not only the camera
    speed, turn = motion_columns(load_spec(spec_file("tracelines")))
    assert len(speed) == 3 and len(turn) == 4


def test_ranked_by_the_motion_a_shaking_copy_as_fast_as_its_recording_gives_way_to_a_steady_hand(tmp_path):
    from fastrl.runner.chosen import rank_recordings

    spec = load_spec(NO_EXPERT)
    env = FastEnv(spec)
    for traj in make_cohort(spec, 3, 3, seed=0):
        Trajectory(traj.time, traj.portal, traj.meta).save(tmp_path / f"{traj.meta['subject']}.npz")
        if traj.meta["skill"] == 3:  # each expert's shaking copy takes as long, and comes first by name
            shaking = with_overlays(env, traj, {"jitter": 1.0}, 0)
            Trajectory(shaking.time, shaking.portal, shaking.meta).save(tmp_path / f"A-{traj.meta['subject']}.npz")
    by_time, _ = rank_recordings(spec, [tmp_path], "time", 3)
    by_motion, _ = rank_recordings(spec, [tmp_path], "motion", 3)
    assert [s.name for s, _ in by_time[:3]] == ["A-L3-S03", "L3-S03", "A-L3-S02"]  # two shaking hands of three
    assert [s.name for s, _ in by_motion[:3]] == ["L3-S03", "A-L3-S03", "L3-S02"]
    assert sorted(s.name for s, _ in by_motion) == sorted(s.name for s, _ in by_time)
    assert by_motion[2][0].scores["motion"] > by_motion[3][0].scores["motion"] + 10  # the steady hand, likelier
    assert [t is not None for _, t in by_motion].count(True) == 3  # the best 3 keep theirs, one read again
    np.testing.assert_array_equal(by_motion[2][1].portal, Trajectory.load(tmp_path / "L3-S02.npz").portal)
    with pytest.raises(ValueError, match="needs the K"):
        rank_recordings(spec, [tmp_path], "motion")


def chosen(runs: Path) -> list[dict]:
    """The recordings the assessment under `runs` learned from."""
    return json.loads(next(runs.glob("medial_pair/*-assess-airl-s0/protocol.json")).read_text())["chosen"]


@pytest.mark.slow  # trains end to end
def test_assess_scores_the_motion_and_a_shaking_copy_below_its_recording(tmp_path):
    spec = load_spec(NO_EXPERT)
    cohort = tmp_path / "cohort"
    cohort.mkdir()
    trajs = list(make_cohort(spec, 3, 2, seed=0))
    for traj in trajs:
        Trajectory(traj.time, traj.portal, traj.meta).save(cohort / f"{traj.meta['subject']}.npz")
    expert = trajs[-1]  # the second best: its shaking copy, a little slower, is third
    assert expert.meta["subject"] == "L3-S02"
    shaking = with_overlays(FastEnv(spec), expert, {"jitter": 1.0}, 0)
    Trajectory(shaking.time, shaking.portal, {**shaking.meta, "subject": "shaking"}).save(cohort / "shaking.npz")

    out = tmp_path / "report" / "scores.json"
    args = ["assess", str(cohort), "--spec", str(NO_EXPERT), "--top", "2", "-o", str(out), "--runs", str(tmp_path)]
    res = CliRunner().invoke(app, [*args, "--no-progress", "--no-pictures"])
    assert res.exit_code == 0, res.output
    report = json.loads(out.read_text())
    assert "motion" in report["scores"] and "motion" in report["ranking"]
    motion = {r["file"]: r["motion"] for r in report["trajectories"]}
    assert "shaking" not in {c["file"] for c in chosen(tmp_path)}  # the motion model is the best 2's
    assert motion["shaking"] < motion[expert.meta["subject"]] - 100

    learned = next(tmp_path.glob("medial_pair/*-assess-airl-s0/learned"))
    assert (learned / "networks" / FILE).is_file()
    again = tmp_path / "again" / "scores.json"
    res = CliRunner().invoke(app, ["score", "--run", str(learned), str(cohort), "-o", str(again), "--no-progress"])
    assert res.exit_code == 0, res.output
    assert {r["file"]: r["motion"] for r in json.loads(again.read_text())["trajectories"]} == motion


def test_the_report_warns_of_a_learned_score_that_ranks_unlike_the_motion():
    from fastrl.assess.report import build_report
    from fastrl.assess.scoring import TrajectoryScores

    levels = np.repeat([1, 2, 3, 4, 5], 4)
    rng = np.random.default_rng(0)
    scored = []
    for i, level in enumerate(levels):
        scores = {"heuristic": 1.0, "reward": float(rng.normal()), "value": float(level), "potential": None}
        scores |= {"motion": 10.0 * level, "subtasks": 1.0, "path_length": 0.1, "time": 30.0 - level}
        scored.append(TrajectoryScores(f"f{i}", {"skill": int(level)}, scores | {"smoothness": -5.0}, None, None))
    references = {"random": {}, "expert": {}}
    warnings = build_report(scored, references, [], learned=True)["warnings"]
    assert [w.split(":")[0] for w in warnings if "ranks unlike the motion" in w] == ["reward"]  # value ranks as it


@pytest.mark.slow  # trains end to end, twice
def test_the_motion_term_weighs_in_the_learned_reward_and_value_and_leaves_the_generator_as_it_was(tmp_path):
    from fastrl.assess.scoring import Scorer, subtasks_reached
    from fastrl.irl.networks import load_networks

    spec = load_spec(NO_EXPERT)
    cohort = tmp_path / "cohort"
    cohort.mkdir()
    for traj in make_cohort(spec, 3, 2, seed=0):
        Trajectory(traj.time, traj.portal, traj.meta).save(cohort / f"{traj.meta['subject']}.npz")

    def assess(name: str, *sets: str) -> tuple[dict, Path]:
        """Each trajectory's report row and the learned run of an assessment with these spec changes."""
        out, runs = tmp_path / name / "scores.json", tmp_path / name
        args = ["assess", str(cohort), "--spec", str(NO_EXPERT), "--top", "2", "-o", str(out), "--runs", str(runs)]
        res = CliRunner().invoke(app, [*args, *sets, "--no-progress", "--no-pictures"])
        assert res.exit_code == 0, res.output
        rows = {r["file"]: r for r in json.loads(out.read_text())["trajectories"]}
        return rows, next(runs.glob("medial_pair/*-assess-airl-s0/learned"))

    weighed, learned = assess("weighed", "--set", "irl.discriminator.motion=2")
    plain, _ = assess("plain")
    model = MotionModel.load(learned / "networks" / FILE)
    assert model.reward_weight > 0
    assert 0 < model.value_weight < model.reward_weight  # AIRL's generator learns from its reward scaled down
    gamma = load_networks(learned / "networks").gamma
    scorer = Scorer(spec)
    for path in sorted(cohort.glob("*.npz")):
        scored, obs = scorer.replayed(scorer.load_file(path))
        moves_there = model.log_density(step_motion(obs, motion_columns(spec)))[1:]
        reached = subtasks_reached(scored.meta)
        term, ahead = model.reward(moves_there).sum(), model.value(moves_there, gamma).sum()
        row, before = weighed[path.stem], plain[path.stem]
        assert term < 0 and ahead < 0
        assert row["reward_raw"] == pytest.approx(before["reward_raw"] + term / reached)
        assert row["value_raw"] == pytest.approx(before["value_raw"] + ahead / reached)  # the same generator's critic
        assert row["motion"] == before["motion"]
