"""Synthetic trainees: each skill parameter costs heuristic return, cohorts are reproducible and labelled."""

from dataclasses import replace

import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.data import Trajectory, load_trajectories
from fastrl.data.cohort import level_table, make_cohort, replayed_figures
from fastrl.data.replay import rollout_trajectory
from fastrl.data.skill import NOVICE, PARAMETERS, SkillProfile, profile_for_level
from fastrl.data.trainee import Trainee

from ..conftest import spec_file

SEEDS = (0, 1, 2, 3)
# The first two avatars of ImageCentring with a time limit that binds for a slowed trainee.
SHORT = {
    "task": {
        "avatars": [
            {"surface": "plate", "at": [0.0, 0.0], "heading_deg": 90},
            {"surface": "plate", "at": [-0.05, 0.04], "heading_deg": 45},
        ]
    },
    "episode": {"time_limit": 9.0},
}


@pytest.fixture(scope="module")
def short_env():
    """Two-avatar ImageCentring, discrete actions."""
    return fastrl.make(spec_file("imagecentring"), **SHORT)


@pytest.fixture(scope="module")
def periscoping_env():
    """Periscoping as bundled: the task where the light cable matters."""
    return fastrl.make(spec_file("periscoping"))


def mean_return(env, profile: SkillProfile) -> float:
    """Mean heuristic return of a trainee over SEEDS."""
    totals = []
    for seed in SEEDS:
        trainee = Trainee(env, profile, seed)
        obs, _ = env.reset(seed=seed)
        trainee.reset()
        total, done = 0.0, False
        while not done:
            obs, r, term, trunc, _ = env.step(trainee.act(obs))
            total += r
            done = term or trunc
        totals.append(total)
    return float(np.mean(totals))


# Each parameter alone at a moderate and a strong value; the gaps are wide enough that the mean return over
# SEEDS falls by several points at each (optics: about 2 points, on the full Periscoping task).
STRENGTHS = {
    "motor_noise": (0.3, 0.6),
    "tremor": (0.5, 1.0),
    "delay": (0.15, 0.35),
    "overshoot": (6.0, 15.0),
    "hesitation": (0.1, 0.25),
    "wander": (0.4, 0.9),
    "optics": (0.5, 1.0),
    "idle": (0.5, 1.5),
    "slowness": (0.3, 0.6),
    "depth": (10.0, 25.0),
    "aim": (3.0, 6.0),
    "horizon": (6.0, 12.0),
    "detour": (0.5, 1.0),
    "dither": (0.15, 0.3),
    "bump": (0.02, 0.05),
}


def test_strengths_cover_every_parameter():
    assert set(STRENGTHS) == set(PARAMETERS)


@pytest.mark.parametrize("name", PARAMETERS)
def test_each_parameter_alone_lowers_the_heuristic_return(name, short_env, periscoping_env):
    env = periscoping_env if name == "optics" else short_env
    values = (0.0, *STRENGTHS[name])
    returns = [mean_return(env, SkillProfile(**{name: v})) for v in values]
    assert returns[0] > returns[1] > returns[2], (name, values, returns)


def test_zero_profile_is_the_scripted_expert(short_env):
    from fastrl.agents.expert import ScriptedExpert

    expert = ScriptedExpert(short_env)
    trainee = Trainee(short_env, SkillProfile(), seed=5)
    a, _ = rollout_trajectory(short_env, expert.act, 5, {"source": "expert"}, expert.reset)
    b, _ = rollout_trajectory(short_env, trainee.act, 5, {"source": "synthetic"}, trainee.reset)
    np.testing.assert_array_equal(a.portal, b.portal)
    np.testing.assert_array_equal(a.actions, b.actions)


def test_same_seed_same_trajectory_other_seed_another(short_env):
    spec = short_env.unwrapped.task_spec
    first = list(make_cohort(spec, 2, 2, seed=7, env=short_env))
    again = list(make_cohort(spec, 2, 2, seed=7, env=short_env))
    other = list(make_cohort(spec, 2, 2, seed=8, env=short_env))
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a.portal, b.portal)
        np.testing.assert_array_equal(a.actions, b.actions)
        assert a.meta == b.meta
    novice_a, novice_b = first[0], other[0]
    assert novice_a.portal.shape != novice_b.portal.shape or not np.array_equal(novice_a.portal, novice_b.portal)


def test_meta_carries_level_subject_and_profile(short_env):
    spec = short_env.unwrapped.task_spec
    cohort = list(make_cohort(spec, 3, 2, seed=0, env=short_env))
    assert [t.meta["skill"] for t in cohort] == [1, 1, 2, 2, 3, 3]
    assert [t.meta["subject"] for t in cohort] == ["L1-S01", "L1-S02", "L2-S01", "L2-S02", "L3-S01", "L3-S02"]
    assert [t.meta["seed"] for t in cohort] == list(range(6))
    for t in cohort:
        assert t.meta["source"] == "synthetic" and t.meta["levels"] == 3
        assert t.meta["profile"] == profile_for_level(t.meta["skill"], 3).as_dict()


def test_replayed_return_rises_with_level(short_env):
    spec = short_env.unwrapped.task_spec
    rows = [
        {"skill": t.meta["skill"], **replayed_figures(short_env, t)}
        for t in make_cohort(spec, 3, 3, seed=0, env=short_env)
    ]
    means = [e["return"] for e in level_table(rows)]
    assert means[0] < means[1] < means[2], means


def test_profiles_grow_from_expert_to_novice():
    assert profile_for_level(5, 5) == SkillProfile()
    assert profile_for_level(1, 5) == NOVICE
    for level in range(1, 5):
        worse, better = profile_for_level(level, 5).as_dict(), profile_for_level(level + 1, 5).as_dict()
        assert all(worse[k] > better[k] for k in PARAMETERS if NOVICE.as_dict()[k] > 0)
    with pytest.raises(ValueError):
        profile_for_level(0, 5)
    with pytest.raises(ValueError):
        profile_for_level(1, 1)
    with pytest.raises(ValueError):
        replace(NOVICE, motor_noise=1.5)


def test_cli_writes_one_loadable_file_per_subject(tmp_path):
    out = tmp_path / "cohort"
    result = CliRunner().invoke(
        app,
        [
            "cohort",
            str(spec_file("tracelines")),
            "--levels",
            "2",
            "--per-level",
            "2",
            "-o",
            str(out),
            "--seed",
            "3",
            "--set",
            "episode.time_limit=4",
            "--no-progress",
        ],
    )
    assert result.exit_code == 0, result.output
    files = sorted(out.glob("*.npz"))
    assert [f.name for f in files] == ["L1-S01.npz", "L1-S02.npz", "L2-S01.npz", "L2-S02.npz"]
    trajectories, errors = load_trajectories([out])
    assert errors == [] and len(trajectories) == 4
    assert sorted(Trajectory.load(f).meta["skill"] for f in files) == [1, 1, 2, 2]
    assert "level" in result.output


def test_cli_bad_spec_exits_2(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nscene: {kind: nowhere}\n")
    result = CliRunner().invoke(app, ["cohort", str(bad), "-o", str(tmp_path / "c")])
    assert result.exit_code == 2
    assert not (tmp_path / "c").exists()
