"""`fastrl sweep` on a real two-node Ray cluster (loopback): trials on both nodes, complete run dirs, retry, resume."""

import json

import pytest
from safetensors import safe_open
from typer.testing import CliRunner

from fastrl.cli import app
from fastrl.runner.sweep.plan import SweepError, create_sweep, parse_grid, plan, trial_overrides
from fastrl.spec import load_spec

from ..conftest import spec_file
from .test_runner import TINY, rrd_verify

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

ray = pytest.importorskip("ray")  # on loopback only: tests/conftest.py sets RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0

SWEEP_TINY = [*TINY, "train.timesteps=128"]


def sets(extra=()):
    """CLI --set arguments for the tiny budget."""
    return [a for kv in [*SWEEP_TINY, *extra] for a in ("--set", kv)]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A real Ray cluster of two nodes (one CPU each) on this machine, as `--address` targets. Its processes get
    a cache of their own: each trial evaluates the scripted expert (3 s), as on a new machine, so a sweep's two
    trials overlap in time; with the expert remembered by earlier tests, one could end before the other started
    and both ran on one node."""
    from ray.cluster_utils import Cluster

    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("FASTRL_CACHE", str(tmp_path_factory.mktemp("cluster-cache")))  # inherited by the raylets
        c = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
        c.add_node(num_cpus=1)
        c.wait_for_nodes()
    yield c
    if ray.is_initialized():
        ray.shutdown()
    c.shutdown()


def node_ids(cluster) -> set[str]:
    """The node ids of a cluster, read through a short-lived driver connection."""
    ray.init(address=cluster.address, log_to_driver=False)
    try:
        alive = [n for n in ray.nodes() if n["Alive"]]
        assert {n["NodeManagerAddress"] for n in alive} == {"127.0.0.1"}, "the test cluster must stay on loopback"
        return {n["NodeID"] for n in alive}
    finally:
        ray.shutdown()


def sweep_cli(args):
    """Invoke `fastrl sweep` in-process."""
    return CliRunner().invoke(app, ["sweep", *args])


def test_grid_plan_names_every_trial_and_bad_grids_are_one_line_errors(tmp_path):
    grid = parse_grid(["train.ppo.learning_rate=1e-3,3e-4", "train.n_envs=2,4"])
    configs, trials = plan(grid, [0, 1])
    assert len(configs) == 4 and len(trials) == 8
    assert trials[0]["name"] == "c0_learning_rate=1e-3_n_envs=2_s0"
    assert trial_overrides(trials[1]) == ["train.ppo.learning_rate=1e-3", "train.n_envs=2", "train.seed=1"]
    with pytest.raises(SweepError, match="KEY=V1,V2"):
        parse_grid(["train.ppo.learning_rate"])
    res = sweep_cli([str(spec_file("tracelines")), "--grid", "train.n_envs=2,zero", "-o", str(tmp_path / "s")])
    assert res.exit_code == 2
    assert "train.n_envs" in res.output and "Traceback" not in res.output


def test_configurations_listed_one_by_one_are_the_trials_not_their_product(tmp_path):
    sn, cr = "irl.discriminator.spectral_norm", "irl.discriminator.current_rollout"
    variants = [{sn: "true", cr: "true"}, {sn: "true", cr: "false"}, {sn: "false", cr: "true"}]  # Fig. 5's three
    folder = create_sweep(spec_file("tracelines"), SWEEP_TINY, {}, [0, 1], 1, tmp_path / "s", variants)
    manifest = json.loads((folder / "sweep.json").read_text())
    assert [c["setting"] for c in manifest["configs"]] == variants and len(manifest["trials"]) == 6
    assert manifest["grid"] == {sn: ["true", "false"], cr: ["true", "false"]}  # the results table's columns
    assert trial_overrides(manifest["trials"][5]) == [f"{sn}=false", f"{cr}=true", "train.seed=1"]
    with pytest.raises(SweepError, match="same keys"):
        create_sweep(spec_file("tracelines"), SWEEP_TINY, {}, [0], 1, tmp_path / "t", [{sn: "true"}, {cr: "true"}])
    with pytest.raises(SweepError, match="not both"):
        create_sweep(spec_file("tracelines"), SWEEP_TINY, {sn: ["true"]}, [0], 1, tmp_path / "u", variants)


def test_sweep_on_a_two_node_cluster_runs_trials_on_both_nodes(cluster, tmp_path):
    folder = tmp_path / "sweep"
    args = [str(spec_file("tracelines")), *sets(), "--grid", "train.ppo.learning_rate=1e-3,3e-4", "--seeds", "0"]
    res = sweep_cli([*args, "--address", cluster.address, "-o", str(folder)])
    assert res.exit_code == 0, res.output
    assert "best configuration: c" in res.output
    summary = json.loads((folder / "results.json").read_text())
    assert [r["seeds"] for r in summary["rows"]] == [1, 1]
    assert {t["node_id"] for t in summary["trials"]} == node_ids(cluster)  # one trial on each node
    for t in summary["trials"]:
        run = folder / t["trial"]
        for name in ("spec.yaml", "model.xml", "meta.json", "eval.json", "final", "networks"):
            assert (run / name).exists(), (run, name)
        assert json.loads((run / "meta.json").read_text())["status"] == "done"
        assert json.loads((run / "trial.json").read_text())["torch_threads"] == 1
        assert load_spec(run / "spec.yaml").train.workers == 1  # one CPU per trial: no env worker processes
        assert "1 file verified" in rrd_verify(run / "recording.rrd")
        with safe_open(str(run / "networks" / "value.safetensors"), "pt") as f:  # a fresh run's standard file
            assert json.loads(f.metadata()["fastrl"])["parts"]["v"][0]["type"] == "linear" and "v.0.weight" in f.keys()
    header = (folder / "results.csv").read_text().splitlines()[0]
    assert header.startswith("config,train.ppo.learning_rate,seeds,success_mean,success_sd")
    assert (folder / "results.png").stat().st_size > 10_000


def test_failed_trial_is_retried_once_and_resume_redoes_only_unfinished_trials(cluster, tmp_path):
    from fastrl.runner import start_run

    folder = tmp_path / "sweep"
    create_sweep(spec_file("tracelines"), SWEEP_TINY, {}, [0, 1, 2], 1, folder)
    manifest = json.loads((folder / "sweep.json").read_text())
    done, blocked, todo = (folder / t["name"] for t in manifest["trials"])
    # a trial finished before the interruption: an ordinary run with the trial's own overrides
    start_run(folder / "spec.yaml", trial_overrides(manifest["trials"][0]), progress=False, into=done)
    before = (done / "eval.json").stat().st_mtime_ns, (done / "meta.json").read_text()
    blocked.write_text("a file where the trial's run directory should go")  # every attempt fails

    res = sweep_cli(["--resume", str(folder), "--address", cluster.address])
    assert res.exit_code == 1, res.output
    assert "3 trials, 1 already finished, 2 to run" in res.output
    assert f"trial {blocked.name} failed twice: " in res.output and "FileExistsError" in res.output
    attempts = [line.split()[0] for line in (folder / "attempts.log").read_text().splitlines()]
    assert sorted(attempts) == sorted([blocked.name, blocked.name, todo.name])  # retried once; finished one skipped
    assert ((done / "eval.json").stat().st_mtime_ns, (done / "meta.json").read_text()) == before

    blocked.unlink()
    res = sweep_cli(["--resume", str(folder), "--address", cluster.address])
    assert res.exit_code == 0, res.output
    assert "3 trials, 2 already finished, 1 to run" in res.output
    attempts = [line.split()[0] for line in (folder / "attempts.log").read_text().splitlines()]
    assert attempts.count(todo.name) == 1 and attempts.count(blocked.name) == 3
    summary = json.loads((folder / "results.json").read_text())
    assert summary["rows"][0]["seeds"] == 3 and summary["failed"] == []
    assert ((done / "eval.json").stat().st_mtime_ns, (done / "meta.json").read_text()) == before
