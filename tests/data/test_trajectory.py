"""The trajectory contract: round trip, checks, demonstrations that replay to identical observations."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.data import Trajectory, TrajectoryError
from fastrl.data.replay import replay

from ..conftest import spec_file


def test_round_trip_keeps_every_field(tmp_path):
    t = Trajectory(
        np.arange(4) * 0.05,
        np.random.default_rng(0).normal(size=(4, 5)),
        {"spec": "x", "source": "human", "subject": "a"},
        np.arange(3),
    )
    back = Trajectory.load(t.save(tmp_path / "t.npz"))
    assert np.array_equal(back.time, t.time) and np.array_equal(back.portal, t.portal)
    assert back.meta == t.meta and np.array_equal(back.actions, t.actions)


@pytest.mark.parametrize(
    "time, portal, meta, why",
    [
        (np.zeros(1), np.zeros((1, 5)), {}, "T >= 2"),
        (np.arange(3.0), np.zeros((3, 4)), {}, "shape (3, 5)"),
        (np.arange(3.0), np.array([[0, 0, np.nan, 0, 0]] * 3), {}, "non-finite"),
        (np.array([0.0, 0.1, 0.1]), np.zeros((3, 5)), {}, "increase"),
        (np.arange(3.0), np.zeros((3, 5)), {"source": "robot"}, "meta.source"),
    ],
)
def test_contract_violations_are_named(time, portal, meta, why):
    with pytest.raises(TrajectoryError, match=why.replace("(", r"\(").replace(")", r"\)")):
        Trajectory(time, portal, meta)


def test_corrupt_and_foreign_files_are_reported_by_name(tmp_path):
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(TrajectoryError, match="junk.npz"):
        Trajectory.load(tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(TrajectoryError, match="missing arrays"):
        Trajectory.load(tmp_path / "other.npz")


def test_expert_demos_replay_to_identical_observations(tmp_path):
    res = CliRunner().invoke(
        app,
        [
            "demos",
            "--expert",
            str(spec_file("tracelines")),
            "-n",
            "2",
            "-o",
            str(tmp_path),
            "--seed",
            "5",
            "--no-progress",
        ],
    )
    assert res.exit_code == 0, res.output
    files = sorted(tmp_path.glob("*.npz"))
    assert len(files) == 2
    traj = Trajectory.load(files[0])
    assert traj.meta["source"] == "expert" and traj.meta["seed"] == 5
    assert traj.meta["subtasks"] == traj.meta["subtasks_total"]
    env = fastrl.make(spec_file("tracelines"))
    from fastrl.agents.expert import ScriptedExpert
    from fastrl.data.replay import rollout_trajectory

    expert = ScriptedExpert(env)
    again, observations = rollout_trajectory(env, expert.act, 5, {"source": "expert"}, expert.reset)
    assert np.array_equal(again.portal, traj.portal)
    replayed, infos, _ = replay(fastrl.make(spec_file("tracelines")), traj)
    np.testing.assert_allclose(replayed, observations, atol=1e-9)
    assert infos[-1]["success"]
    assert json.loads(json.dumps(traj.meta)) == traj.meta


def test_plain_numpy_files_follow_the_contract_both_ways(tmp_path):
    env = fastrl.make(spec_file("tracelines"))
    from fastrl.data.replay import expert_trajectories

    ours = expert_trajectories(env, [2])[0]
    meta = {"spec": "tracelines", "subject": "lab-7", "skill": "expert", "source": "human", "seed": 2}
    np.savez(tmp_path / "theirs.npz", time=ours.time, portal=ours.portal, meta=np.array(json.dumps(meta)))
    theirs = Trajectory.load(tmp_path / "theirs.npz")  # written without our code, no actions
    assert theirs.meta == meta and theirs.actions is None
    _, infos, _ = replay(env, theirs)
    assert infos[-1]["success"] and infos[-1]["subtask"] == ours.meta["subtasks"]
    with np.load(ours.save(tmp_path / "ours.npz"), allow_pickle=False) as z:  # and read back without our code
        assert np.array_equal(z["portal"], ours.portal) and np.array_equal(z["actions"], ours.actions)
        assert json.loads(str(z["meta"]))["source"] == "expert"
