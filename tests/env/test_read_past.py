"""Measured poses (read off video, imported from a tracker) replay reading an avatar passed when the next one is held
while it is current: a hold their error lost does not lose every avatar after it. Poses given as they were replay
by the live task's rule, and no avatar is credited without a hold next to it."""

import numpy as np
import pytest

from fastrl.data.replay import expert_trajectories, measured, replay
from fastrl.data.trajectory import Trajectory
from fastrl.env.column_replay import replay_columns
from fastrl.env.fast_env import FastEnv
from fastrl.model.kinematics import Kinematics, solve_view
from fastrl.spec import load_spec

from ..conftest import spec_file

VIDEO = {"portal_from": "video"}
TRACKER = {"imported_from": "p07.csv"}


@pytest.fixture(scope="module")
def tracelines():
    env = FastEnv(load_spec(spec_file("tracelines")))
    return env, expert_trajectories(env, [3])[0]


def subtasks(env, traj: Trajectory) -> list[int]:
    """Subtasks done at each replayed sample, step by step (the replay by columns must give the same, bit for bit)."""
    obs, infos, rewards = replay(env, traj)
    done = [int(i["subtask"]) for i in infos]
    by_columns = replay_columns(env, traj.portal, int(traj.meta["seed"]), measured(traj))
    assert by_columns.subtasks == done[-1] and np.array_equal(by_columns.observations, obs)
    assert np.array_equal(by_columns.rewards, rewards)
    return done


def test_the_experts_recording_replays_as_it_ran_either_way(tracelines):
    env, traj = tracelines
    for meta in ({}, VIDEO, TRACKER):
        done = subtasks(env, Trajectory(traj.time, traj.portal, {**traj.meta, **meta}))
        assert done[-1] == traj.meta["subtasks"] == traj.meta["subtasks_total"] and len(done) == len(traj.time)
        assert all(b - a in (0, 1) for a, b in zip(done, done[1:]))  # one avatar at a time, as the live task


def test_a_hold_measurement_lost_loses_that_avatar_alone(tracelines):
    env, traj = tracelines
    done = subtasks(env, traj)
    k = 4
    hold, next_hold = done.index(k + 1) - 1, done.index(k + 2) - 1  # the first of the dwell's two green samples
    portal = traj.portal.copy()
    portal[hold:next_hold, 0] += np.radians(10.0)  # from avatar k's hold to avatar k + 1's, 10 degrees off in pitch
    for meta in (VIDEO, TRACKER):
        again = subtasks(env, Trajectory(traj.time, portal, {**traj.meta, **meta}))
        assert again[-1] == done[-1] and len(again) == len(done)  # every avatar, done by the same sample
        assert again[next_hold] == k and again[next_hold + 1] == k + 2  # k passed with k + 1
    given = subtasks(env, Trajectory(traj.time, portal, traj.meta))  # as it was: the live task's reading
    assert given[-1] == k and len(given) == len(traj.time)  # the lost hold loses every avatar after it


@pytest.mark.parametrize("held, measured_credit, given_credit", [(0, 1, 1), (1, 2, 0), (2, 0, 0)])
def test_a_held_view_credits_its_avatar_and_at_most_the_one_before(tracelines, held, measured_credit, given_credit):
    env, traj = tracelines
    q, _ = solve_view(Kinematics(env.unwrapped.task), held, traj.portal[0])
    still = np.repeat(q[None], 41, axis=0)
    assert subtasks(env, Trajectory(np.arange(41) / 20.0, still, {**traj.meta, **VIDEO}))[-1] == measured_credit
    assert subtasks(env, Trajectory(np.arange(41) / 20.0, still, traj.meta))[-1] == given_credit
