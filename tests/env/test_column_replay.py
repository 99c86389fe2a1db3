"""Replaying a recording by columns gives, bit for bit, what replaying it step by step gives."""

import numpy as np
import pytest

from fastrl.assess.scoring import held_to_limit
from fastrl.data.cohort import make_cohort
from fastrl.data.replay import replay
from fastrl.env.column_replay import can_replay_columns, replay_columns
from fastrl.env.fast_env import FastEnv
from fastrl.spec import load_spec
from fastrl.terms import OBSERVATION_TERMS, REWARD_FEATURES, TaskState
from fastrl.terms.columns import FEATURE_COLUMNS, OBSERVATION_COLUMNS, Columns
from fastrl.terms.state import _fields

from ..conftest import spec_file


def cohort(spec, env) -> list:
    """A novice, a middling and an expert-like subject, and the best of them stopped at a third; each held still to
    the time limit as scoring holds them."""
    trajs = list(make_cohort(spec, 3, 1, seed=4, env=env, families=("classic", "paused", "jitter")))
    best = trajs[-1]
    trajs.append(type(best)(best.time[: len(best.time) // 3], best.portal[: len(best.time) // 3], best.meta))
    return [held_to_limit(t, spec, len(t.time)) or t for t in trajs]


FIXED = ("time_limit", "dt", "gamma", "fov", "portal_lo", "portal_hi", "subtasks_total")  # the same at every sample


def columns_of(states: list) -> Columns:
    """The columns of a list of TaskStates: each field as an array over them (the fixed ones as they are)."""
    first = states[0]
    return Columns(
        **{
            n: getattr(first, n) if n in FIXED else np.array([getattr(s, n) for s in states])
            for n in _fields(type(first))
        }
    )


def stepwise(env, traj) -> tuple:
    """Observations, rewards, infos, tips and each state of a replay step by step."""
    tips, states = [], []

    def keep(u):
        tips.append(u.state.tip_pos)
        states.append(TaskState())
        states[-1].copy_from(u.state)

    obs, infos, rewards = replay(env, traj, keep)
    return obs, rewards, infos, np.array(tips), states


@pytest.mark.parametrize("name", ["tracelines", "imagecentring", "periscoping", "liver_tour"])
def test_a_replay_by_columns_is_the_replay_step_by_step(name):
    spec = load_spec(spec_file(name))
    env = FastEnv(spec)
    assert can_replay_columns(env)
    endings = set()
    for traj in cohort(spec, env):
        obs, rewards, infos, tips, _ = stepwise(env, traj)
        got = replay_columns(env, traj.portal, int(traj.meta["seed"]))
        assert np.array_equal(got.observations, obs) and got.observations.dtype == obs.dtype
        assert np.array_equal(got.rewards, rewards) and np.array_equal(got.tips, tips)
        assert np.array_equal(got.contacts, [i["contacts"] for i in infos])
        assert (got.subtasks, got.subtasks_total) == (infos[-1]["subtask"], infos[-1]["subtasks_total"])
        endings.add((got.success, len(rewards) < len(traj.time)))
    assert (True, True) in endings and (False, False) in endings  # stopped by success, and replayed to the end


@pytest.mark.parametrize("name", ["tracelines", "periscoping"])  # the line's deviation; the rays
def test_every_array_form_is_its_scalar_term(name):
    spec = load_spec(spec_file(name))
    env = FastEnv(spec)
    states = [s for traj in cohort(spec, env) for s in stepwise(env, traj)[-1]]
    cols = columns_of(states)
    assert set(OBSERVATION_COLUMNS) <= set(OBSERVATION_TERMS) and set(FEATURE_COLUMNS) <= set(REWARD_FEATURES)
    assert {s.completed for s in states} == {True, False} and len({s.subtask for s in states}) > 3
    assert len({s.ray_fraction if name == "periscoping" else s.line_deviation for s in states}) > 3
    for term, form in OBSERVATION_COLUMNS.items():
        expected = np.array([OBSERVATION_TERMS[term].fn(s) for s in states], float)
        assert np.array_equal(np.asarray(form(cols), float).reshape(expected.shape), expected), term
    for feature, form in FEATURE_COLUMNS.items():
        params = {"margin": 0.005} if feature == "distance" else {}  # a narrow margin: the kernel's tails are read
        expected = np.array([REWARD_FEATURES[feature].fn(s, **params) for s in states])
        assert np.array_equal(form(cols, **params), expected), feature


def test_tasks_whose_terms_have_no_array_form_replay_step_by_step():
    assert not can_replay_columns(FastEnv(load_spec(spec_file("triangulation"))))  # an instrument
