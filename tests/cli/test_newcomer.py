"""What a newcomer meets first: the recording opens on the curves, a warning after a run that learned
nothing, `fastrl runs` at 80 columns, flags shown as flags in --help, rich markup rendered."""

import json
import os
import shutil
import subprocess
import sys

import pytest
import typer
from rerun.chunk import RrdReader
from rich.console import Console
from typer.testing import CliRunner

from fastrl.cli import app
from fastrl.runner.train.demos import write_demos
from fastrl.runner.train.learner import demonstrations
from fastrl.spec import load_spec

from ..conftest import spec_file

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

TINY = [
    "train.n_envs=2",
    "train.ppo.n_steps=64",
    "train.ppo.batch_size=64",
    "train.ppo.n_epochs=1",
    "train.log_every=256",
    "evaluate.episodes=2",
    "evaluate.record_episodes=1",
    "evaluate.image_every=10",
    "episode.time_limit=8",
]


@pytest.fixture(scope="module")
def copied_run(tmp_path_factory):
    """A copy of the bundled TraceLines spec trained for 320 timesteps: (CLI result, run directory, runs root)."""
    tmp = tmp_path_factory.mktemp("copied")
    spec = tmp / "my_lines.yaml"
    shutil.copy(spec_file("tracelines"), spec)
    args = ["run", str(spec), "--timesteps", "320", "--runs", str(tmp / "runs"), "--no-progress"]
    res = CliRunner().invoke(app, [*args, *[a for kv in TINY for a in ("--set", kv)]])
    assert res.exit_code == 0, res.output
    (run,) = [p.parent for p in (tmp / "runs").glob("*/*/meta.json")]
    return res, run, tmp / "runs"


def test_a_run_that_learned_nothing_says_so_and_what_to_try(copied_run):
    res, _, _ = copied_run
    warning = [line for line in res.output.splitlines() if line.startswith("warning:")]
    assert len(warning) == 1, res.output
    assert "the scripted expert 100%" in warning[0]
    assert "--timesteps 500000" in warning[0]  # the copied file's own budget
    assert str(spec_file("tracelines").resolve()) in warning[0]  # the bundled spec, tuned


def test_the_expert_level_agent_gets_no_warning(tmp_path):
    from fastrl.runner.train.advice import learning_advice

    run = tmp_path / "run"
    run.mkdir()
    shutil.copy(spec_file("tracelines"), run / "spec.yaml")
    (run / "meta.json").write_text(json.dumps({"trained_timesteps": 500000}))
    figures = {"subtasks_completed": 0.9, "success_rate": 0.9}
    (run / "eval.json").write_text(json.dumps({"agent": figures, "expert": {**figures, "subtasks_completed": 1.0}}))
    assert learning_advice(run, spec_file("tracelines")) is None


def test_the_recording_opens_on_the_training_curves(copied_run):
    """The time panel starts on `timesteps` at its end, the plots span the whole timeline, the episode is there."""
    _, run, _ = copied_run
    reader = RrdReader(run / "recording.rrd")
    blueprint = list(reader.stream(store=reader.blueprints()[0]).to_chunks())

    def values(component):
        return [
            v
            for c in blueprint
            for n in c.to_record_batch().schema.names
            if n == component
            for v in c.to_record_batch().column(n).to_pylist()
        ]

    assert values("TimePanelBlueprint:timeline") == [["timesteps"]]
    assert values("TimePanelBlueprint:play_state") == [[3]]  # following: the cursor at the end
    assert len(values("TimeAxis:view_range")) >= 3  # every time series view over the whole timeline

    trained = json.loads((run / "meta.json").read_text())["trained_timesteps"]
    recording = list(reader.stream().to_chunks())

    def at(entity):
        return {
            t
            for c in recording
            if c.entity_path == entity and "timesteps" in c.timeline_names
            for t in c.to_record_batch().column("timesteps").to_pylist()
        }

    assert at("/world/eval/ep_00/camera") == {trained}  # the episode's final state at the curves' end
    assert max(at("/metrics/train/episode/return")) == trained  # the curves end where training ended
    assert not at("/metrics/eval/ep_00/reward")  # per-step scalars stay on `step`


def test_runs_table_fits_80_columns(copied_run):
    _, run, runs = copied_run
    env = {**os.environ, "COLUMNS": "80", "PYTHONPATH": os.pathsep.join(sys.path)}
    res = subprocess.run(
        [sys.executable, "-m", "fastrl.cli", "runs", "--runs", str(runs)],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert max(len(line) for line in lines) <= 80, res.stdout
    name = run.relative_to(runs).as_posix()
    assert any(name in line and "done" in line for line in lines), res.stdout  # one run, one line


def test_help_shows_flags_as_flags():
    group = typer.main.get_command(app)
    commands = [[]] + [[name] for name in group.commands]
    assert len(commands) > 8
    for args in commands:
        res = CliRunner().invoke(app, [*args, "--help"], terminal_width=120)
        assert res.exit_code == 0, res.output
        assert "<bool>" not in res.output, (args, res.output)
    run_help = CliRunner().invoke(app, ["run", "--help"], terminal_width=120).output
    assert "--no-progress" in run_help and "<int>" in run_help  # values keep their type


def test_skipped_demonstrations_render_markup_and_show_user_text_verbatim(tmp_path):
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=4"])
    folder = tmp_path / "demos"
    good = write_demos(folder, 1, 0, expert_spec=spec, progress=False)[0]
    assert good.exists()  # a trajectory without actions is learned from (actions recovered): a broken file is skipped
    (folder / "[red]ann[bold].npz").write_bytes(b"not a trajectory")
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=4", f"irl.demonstrations.path={folder}"])
    console = Console(record=True, width=200, color_system="truecolor", force_terminal=True)
    assert len(demonstrations(spec, tmp_path, console, progress=False)) == 1
    styled = console.export_text(clear=False, styles=True)
    text = console.export_text()
    assert "skipped " in text and "[red]ann[bold].npz" in text and "[yellow]" not in text
    assert "\x1b[33mskipped" in styled  # 'skipped' in yellow
