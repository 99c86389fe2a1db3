"""Trajectories with actions round-trip through a local Minari dataset (`fastrl export --minari`, `fastrl import`)."""

import os

import numpy as np
import pytest
from typer.testing import CliRunner

from fastrl.cli import app
from fastrl.data.trajectory import Trajectory, load_trajectories

from ..conftest import spec_file

minari = pytest.importorskip("minari")


def cli(*args):
    """Invoke the CLI in-process."""
    return CliRunner().invoke(app, [str(a) for a in args])


def test_a_cohort_and_demonstrations_round_trip_through_minari(tmp_path, monkeypatch):
    spec = spec_file("tracelines")
    res = cli("cohort", spec, "--levels", 2, "--per-level", 1, "-o", tmp_path / "trajs", "--no-progress")
    assert res.exit_code == 0, res.output
    res = cli("demos", "--expert", spec, "-n", 1, "-o", tmp_path / "trajs", "--no-progress")
    assert res.exit_code == 0, res.output
    original, errors = load_trajectories([tmp_path / "trajs"])
    assert len(original) == 3 and not errors and all(t.actions is not None for t in original)

    res = cli("export", tmp_path / "trajs", "--minari", tmp_path / "datasets", "--spec", spec)
    assert res.exit_code == 0, res.output
    assert "fastrl/tracelines-v0" in res.output

    # any Minari user reads it by id from the local folder, with observations as replayed
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "datasets"))
    dataset = minari.load_dataset("fastrl/tracelines-v0")
    assert dataset.total_episodes == 3 and dataset.action_space.n == 11
    episodes = list(dataset.iterate_episodes())
    for ep, traj in zip(episodes, original):
        assert ep.observations.shape == (len(traj.time), dataset.observation_space.shape[0])
        assert np.array_equal(ep.actions, traj.actions) and len(ep.rewards) == len(traj.time) - 1
        assert ep.terminations[-1] or ep.truncations[-1]
    assert {bool(ep.terminations[-1]) for ep in episodes} == {True, False}  # the expert finishes, novices time out

    res = cli("import", "--minari", tmp_path / "datasets", "-o", tmp_path / "back")
    assert res.exit_code == 0, res.output
    back = [Trajectory.load(p) for p in sorted((tmp_path / "back").glob("*.npz"))]
    assert len(back) == 3
    for a, b in zip(original, back):
        assert np.array_equal(a.time, b.time) and np.array_equal(a.portal, b.portal)
        assert np.array_equal(a.actions, b.actions) and a.meta == b.meta


def test_trajectories_without_actions_and_missing_datasets_are_one_line_errors(tmp_path):
    t = Trajectory(np.arange(3) * 0.05, np.zeros((3, 5)), {"source": "human", "subject": "p1"})
    t.save(tmp_path / "p1.npz")
    res = cli("export", tmp_path / "p1.npz", "--minari", tmp_path / "datasets", "--spec", spec_file("tracelines"))
    assert res.exit_code == 2 and "no actions" in res.output and "Traceback" not in res.output
    res = cli("import", "--minari", tmp_path / "nothing", "-o", tmp_path / "back")
    assert res.exit_code == 2 and "no Minari dataset" in res.output
    assert os.environ.get("MINARI_DATASETS_PATH") is None  # the export leaves the environment as it found it


def test_loose_bodies_round_trip_with_the_grasper_and_the_bodies(tmp_path):
    import fastrl
    from fastrl.agents.expert import ScriptedExpert
    from fastrl.data.minari_io import export_minari, import_minari
    from fastrl.data.replay import rollout_trajectory

    env = fastrl.make(spec_file("loose_bodies"), actions={"mode": "rates"})
    expert = ScriptedExpert(env)
    traj, observations = rollout_trajectory(env, expert.act, 2, {"source": "expert"}, expert.reset)
    export_minari(env, [traj], tmp_path / "datasets", "fastrl/loose-v0")
    (back,) = import_minari(tmp_path / "datasets")
    np.testing.assert_array_equal(back.instruments, traj.instruments)
    np.testing.assert_array_equal(back.bodies, traj.bodies)
    dataset = minari.MinariDataset(tmp_path / "datasets" / "fastrl" / "loose-v0" / "data")
    (ep,) = list(dataset.iterate_episodes())
    np.testing.assert_allclose(ep.observations, observations, atol=1e-6)  # replayed with scope, grasper and bodies
    assert ep.terminations[-1]  # every body ended in the cup on replay too


def recovered_like(original, recovered, seed=3):
    """Same spec, same spaces and the same first observation for the same seed."""
    from fastrl.spec import spec_hash

    assert spec_hash(recovered.unwrapped.task_spec) == spec_hash(original.unwrapped.task_spec)
    assert recovered.observation_space == original.observation_space
    assert recovered.action_space == original.action_space
    np.testing.assert_array_equal(recovered.reset(seed=seed)[0], original.reset(seed=seed)[0])


def test_a_dataset_recovers_its_env_through_minari(tmp_path, monkeypatch):
    """The env_spec names the registered id and carries the spec, overrides included."""
    import fastrl
    from fastrl.agents.expert import ScriptedExpert
    from fastrl.data.minari_io import export_minari
    from fastrl.data.replay import rollout_trajectory

    env = fastrl.make("tracelines", actions={"mode": "rates"})  # the bundled spec, not as bundled
    expert = ScriptedExpert(env)
    traj, _ = rollout_trajectory(env, expert.act, 0, {"source": "expert"}, expert.reset)
    export_minari(env, [traj], tmp_path / "datasets", "fastrl/lines-rates-v0")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "datasets"))
    dataset = minari.load_dataset("fastrl/lines-rates-v0")
    assert dataset.env_spec.id == "fastrl/TraceLines-v0" and dataset.env_spec.entry_point == "fastrl:make"
    recovered = dataset.recover_environment()
    assert recovered.unwrapped.task_spec.actions.mode == "rates"
    recovered_like(env, recovered)
    recovered_like(env, dataset.recover_environment(eval_env=True))


def test_a_dataset_of_a_spec_file_recovers_after_the_file_is_gone(tmp_path, monkeypatch):
    import fastrl

    text = fastrl.spec_path("tracelines").read_text().replace("name: tracelines", "name: my_lines", 1)
    spec = tmp_path / "mine.yaml"
    spec.write_text(text.replace("time_limit: 30", "time_limit: 20", 1))
    res = cli("demos", "--expert", spec, "-n", 1, "-o", tmp_path / "trajs", "--no-progress")
    assert res.exit_code == 0, res.output
    res = cli("export", tmp_path / "trajs", "--minari", tmp_path / "datasets", "--spec", spec)
    assert res.exit_code == 0, res.output
    original = fastrl.make(spec)
    spec.unlink()
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "datasets"))
    dataset = minari.load_dataset("fastrl/my_lines-v0")
    assert dataset.env_spec.id == "fastrl/my_lines-v0"
    recovered = dataset.recover_environment()
    assert recovered.unwrapped.task_spec.episode.time_limit == 20
    recovered_like(original, recovered)
