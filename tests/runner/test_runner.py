"""`fastrl run` end to end on tiny budgets: run directory, recording, overrides, resume, SIGINT, determinism."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from rerun.chunk import RrdReader
from typer.testing import CliRunner

from fastrl.cli import app
from fastrl.spec import load_spec

from ..conftest import spec_file

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

TINY = [
    "train.n_envs=2",
    "train.ppo.n_steps=64",
    "train.ppo.batch_size=64",
    "train.ppo.n_epochs=1",
    "train.log_every=128",
    "train.checkpoint_every=256",
    "evaluate.episodes=2",
    "evaluate.record_episodes=1",
    "evaluate.image_every=10",
    "episode.time_limit=8",
]


def sets(extra=()):
    """CLI --set arguments for the tiny budget."""
    return [a for kv in [*TINY, *extra] for a in ("--set", kv)]


def run_cli(args, runs: Path):
    """Invoke the CLI in-process."""
    return CliRunner().invoke(app, [*args, "--runs", str(runs), "--no-progress"])


def only_run(runs: Path) -> Path:
    """The single run directory under runs."""
    found = list(runs.glob("*/*/meta.json"))
    assert len(found) == 1, found
    return found[0].parent


def rrd_verify(path: Path) -> str:
    """Output of `rerun rrd verify`."""
    res = subprocess.run(
        ["rerun", "rrd", "verify", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "CI": "1"},
    )
    assert res.returncode == 0, res.stderr
    return res.stdout + res.stderr


def recorded(path: Path) -> tuple[set[str], set[str]]:
    """Entity paths and timeline names in a recording."""
    entities, timelines = set(), set()
    for chunk in RrdReader(str(path)).stream():
        entities.add(str(chunk.entity_path))
        timelines.update(chunk.timeline_names)
    return entities, timelines


def test_a_run_directory_is_complete_and_its_recording_valid(tmp_path):
    res = run_cli(["run", str(spec_file("tracelines")), "--timesteps", "512", *sets()], tmp_path)
    assert res.exit_code == 0, res.output
    run = only_run(tmp_path)
    assert run.parent.name == "tracelines" and run.name.endswith("-ppo-s0")
    for name in (
        "spec.yaml",
        "model.xml",
        "meta.json",
        "eval.json",
        "recording.rrd",
        "metrics.jsonl",
        "final/weights.pt",
        "final/normalize.npz",
        "final/state.json",
    ):
        assert (run / name).exists(), name
    assert list((run / "checkpoints").glob("*/weights.pt"))
    meta = json.loads((run / "meta.json").read_text())
    assert meta["status"] == "done" and len(meta["spec_hash"]) == 16 and meta["versions"]["mujoco"]
    assert meta["trained_timesteps"] >= 512
    ev = json.loads((run / "eval.json").read_text())
    assert ev["agent"]["episodes"] == 2 and ev["expert"]["success_rate"] == 1.0
    assert {
        "success_rate",
        "subtasks_completed",
        "return_mean",
        "episode_time_mean",
        "path_length_mean",
        "features_mean",
    } <= set(ev["agent"])
    assert "1 file verified" in rrd_verify(run / "recording.rrd")
    entities, timelines = recorded(run / "recording.rrd")
    assert any(e.startswith("/world/scene") for e in entities)
    assert any(e.startswith("/world/eval/ep_00") for e in entities)
    assert any(e.startswith("/metrics/train") for e in entities)
    assert {"step", "timesteps"} <= timelines
    listing = json.loads(CliRunner().invoke(app, ["runs", "--runs", str(tmp_path), "--json"]).output)
    assert [(r["spec"], r["status"], r["run"]) for r in listing] == [("tracelines", "done", str(run))]
    assert CliRunner().invoke(app, ["runs", "--runs", str(tmp_path)]).exit_code == 0


def test_set_overrides_reach_the_run_and_bad_ones_are_reported(tmp_path):
    res = run_cli(
        ["run", str(spec_file("periscoping")), "--timesteps", "256", "--seed", "3", *sets(["task.cue.dwell=0.2"])],
        tmp_path,
    )
    assert res.exit_code == 0, res.output
    run = only_run(tmp_path)
    assert run.name.endswith("-s3")
    assert load_spec(run / "spec.yaml").task.cue.dwell == 0.2
    bad = run_cli(["run", str(spec_file("periscoping")), "--set", "train.ppo.n_step=64"], tmp_path / "x")
    assert bad.exit_code == 2
    assert "train.ppo.n_step" in bad.output and "did you mean 'n_steps'" in bad.output
    bad = run_cli(["run", str(spec_file("periscoping")), "--algo", "SAC"], tmp_path / "y")
    assert bad.exit_code == 2 and "continuous" in bad.output
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_same_seed_gives_the_same_evaluation(tmp_path):
    figures = []
    for k in range(2):
        res = run_cli(["run", str(spec_file("imagecentring")), "--timesteps", "256", *sets()], tmp_path / str(k))
        assert res.exit_code == 0, res.output
        ev = json.loads((only_run(tmp_path / str(k)) / "eval.json").read_text())
        figures.append([(e["return"], e["subtasks"], e["path_length"]) for e in ev["agent"]["per_episode"]])
    assert figures[0] == figures[1]


def default_sigint() -> None:
    """Undo an inherited SIG_IGN (a suite started in the background ignores SIGINT), so Ctrl-C reaches the CLI."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start_cli(args, cwd: Path) -> subprocess.Popen:
    """The real console script in a subprocess."""
    env = {**os.environ, "CI": "1", "MUJOCO_GL": "egl"}
    return subprocess.Popen(
        [sys.executable, "-m", "fastrl.cli", *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_sigint,
    )


def wait_for(path: Path, proc: subprocess.Popen, timeout: float = 120.0) -> None:
    """Wait until a file exists (training has logged) or fail."""
    t0 = time.time()
    while not path.exists():
        assert proc.poll() is None, proc.communicate()
        assert time.time() - t0 < timeout, "training did not start"
        time.sleep(0.2)


def test_sigint_leaves_a_valid_recording_and_a_checkpoint_then_resume_continues(tmp_path):
    runs = tmp_path / "runs"
    proc = start_cli(
        ["run", str(spec_file("tracelines")), "--timesteps", "200000", "--runs", str(runs), "--no-progress", *sets()],
        tmp_path,
    )
    deadline = time.time() + 120
    while not list(runs.glob("*/*/metrics.jsonl")):
        assert proc.poll() is None, proc.communicate()
        assert time.time() < deadline
        time.sleep(0.2)
    run = list(runs.glob("*/*"))[0]
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and f"fastrl run --resume {run}" in err
    meta = json.loads((run / "meta.json").read_text())
    stopped = meta["trained_timesteps"]
    assert meta["status"] == "interrupted" and 0 < stopped < 200000
    assert "1 file verified" in rrd_verify(run / "recording.rrd")
    ckpts = sorted((run / "checkpoints").glob("*/state.json"))
    assert json.loads(ckpts[-1].read_text())["timesteps"] == stopped

    res = CliRunner().invoke(app, ["run", "--resume", str(run), "--timesteps", str(stopped + 256), "--no-progress"])
    assert res.exit_code == 0, res.output
    final = json.loads((run / "final" / "state.json").read_text())["timesteps"]
    assert final >= stopped + 256
    rows = [json.loads(line)["timesteps"] for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert rows == sorted(rows) and rows[-1] > stopped
    assert "1 file verified" in rrd_verify(run / "recording.rrd")
    assert list(run.glob("recording.part1.rrd"))
    _, timelines = recorded(run / "recording.rrd")
    assert "timesteps" in timelines


@pytest.mark.parametrize("target", ["expert", "run"])
def test_eval_command(tmp_path, target):
    if target == "expert":
        res = CliRunner().invoke(
            app, ["eval", "--expert", str(spec_file("periscoping")), "--episodes", "2", "-o", str(tmp_path / "e.json")]
        )
        assert res.exit_code == 0, res.output
        assert json.loads((tmp_path / "e.json").read_text())["expert"]["success_rate"] == 1.0
    else:
        assert run_cli(["run", str(spec_file("imagecentring")), "--timesteps", "256", *sets()], tmp_path).exit_code == 0
        res = CliRunner().invoke(app, ["eval", str(only_run(tmp_path)), "--episodes", "2"])
        assert res.exit_code == 0, res.output
        assert "agent" in res.output and "expert" in res.output
