"""Damaged files of a real run directory: every command names the file and the fault in one line, never a traceback,
refuses (exit 2) only when it needs that file, and writes nothing over it; `fastrl repair` mends what it can."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from fastrl.cli import app
from fastrl.runner.runs.runfiles import recording_fault

from ..conftest import spec_file
from .test_stops import TINY

pytestmark = pytest.mark.timeout(300)


@pytest.fixture(scope="module")
def done(tmp_path_factory) -> Path:
    """One finished run on a tiny budget (two checkpoints, final/, eval.json, a whole recording)."""
    root = tmp_path_factory.mktemp("runs")
    sets = [a for kv in [*TINY, "train.checkpoint_every=128"] for a in ("--set", kv)]
    args = ["run", str(spec_file("tracelines")), "--timesteps", "256", "--runs", str(root), "--no-progress", *sets]
    env = {**os.environ, "CI": "1", "MUJOCO_GL": "egl"}
    res = subprocess.run([sys.executable, "-m", "fastrl.cli", *args], capture_output=True, text=True, env=env)
    assert res.returncode == 0, res.stderr
    [run] = [p.parent for p in root.glob("*/*/eval.json")]
    return run


def cut(path: Path) -> None:
    """Keep the first half of a file: a half-written copy."""
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def flip(path: Path) -> None:
    """Flip one byte in the middle of a file: a disk fault."""
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))


# damage -> (the file it damages, how, the commands that need that file and so must refuse)
DAMAGES = {
    "meta.json": ("meta.json", cut, {"resume"}),
    "spec.yaml": (
        "spec.yaml",
        lambda p: p.write_text(p.read_text() + "train: [unclosed\n"),
        {"resume", "eval", "score"},
    ),
    "eval.json": ("eval.json", cut, set()),
    "state.json": ("checkpoints/0000000256/state.json", cut, set()),
    "weights.pt": ("final/weights.pt", flip, set()),
    "recording.rrd": ("recording.rrd", lambda p: p.write_bytes(p.read_bytes()[:-300]), {"view"}),
}
COMMANDS = {
    "runs": lambda run, empty: ["runs", "--runs", str(run.parent.parent)],
    "view": lambda run, empty: ["view", str(run)],
    "eval": lambda run, empty: ["eval", str(run), "--episodes", "1"],
    "score": lambda run, empty: ["score", "--run", str(run), str(empty), "--no-progress", "--no-pictures"],
    "resume": lambda run, empty: ["run", "--resume", str(run), "--no-progress"],
}


@pytest.mark.parametrize("damage", sorted(DAMAGES))
def test_each_command_names_a_damaged_file_in_one_line(done, tmp_path, damage):
    """runs, view, eval, score --run, run --resume on a run with one damaged file."""
    where, hurt, needed_by = DAMAGES[damage]
    empty = tmp_path / "no_trajectories"
    empty.mkdir()
    for name, command in COMMANDS.items():
        run = tmp_path / name / "tracelines" / done.name
        shutil.copytree(done, run)
        hurt(run / where)
        before = (run / where).read_bytes()
        res = CliRunner().invoke(app, command(run, empty))
        text = res.output
        assert "Traceback" not in text and isinstance(res.exception, (SystemExit, type(None))), (name, text)
        named = [
            line for line in text.splitlines() if str(run / where) in line or str(run / where.split("/")[0]) in line
        ]
        assert named, (name, damage, text)
        if name in needed_by:
            assert res.exit_code == 2, (name, text)
            assert str(run / where) in res.stderr.splitlines()[-1], (name, text)
            assert "fastrl" in res.stderr.splitlines()[-1] or "restore" in res.stderr.splitlines()[-1]
        elif name in ("runs", "view", "eval"):
            assert res.exit_code == 0, (name, text)
        if name != "resume":  # reading never writes over a damaged file
            assert (run / where).read_bytes() == before, name
    if damage == "meta.json":  # the run is listed, marked, not hidden
        res = CliRunner().invoke(app, ["runs", "--runs", str(tmp_path / "runs"), "--json"])
        assert '"status": "damaged"' in res.output


def test_repair_rebuilds_meta_json_keeping_the_damaged_one_and_the_run_resumes(done, tmp_path):
    """`fastrl repair` mends a half-written meta.json and a footerless recording; then --resume works."""
    run = tmp_path / "tracelines" / done.name
    shutil.copytree(done, run)
    cut(run / "meta.json")
    damaged = (run / "meta.json").read_bytes()
    DAMAGES["recording.rrd"][1](run / "recording.rrd")
    assert recording_fault(run / "recording.rrd") is not None
    res = CliRunner().invoke(app, ["repair", str(run)])
    assert res.exit_code == 0 and "rebuilt" in res.output and "repaired" in res.output, res.output
    assert (run / "meta.json.damaged").read_bytes() == damaged
    assert recording_fault(run / "recording.rrd") is None
    res = CliRunner().invoke(app, ["runs", "--runs", str(tmp_path), "--json"])
    assert '"status": "done"' in res.output and '"problems": []' in res.output, res.output
    res = CliRunner().invoke(app, ["run", "--resume", str(run), "--no-progress", "--timesteps", "384"])
    assert res.exit_code == 0, res.output


def test_the_footer_check_reads_only_the_tail(done, tmp_path):
    """A whole recording passes; one cut by a byte, or padded, does not; a large file is judged as fast as a small."""
    import time

    rrd = tmp_path / "r.rrd"
    shutil.copy(done / "recording.rrd", rrd)
    assert recording_fault(rrd) is None
    with open(rrd, "ab") as f:
        f.write(b"\0")
    assert "no RRD footer" in recording_fault(rrd)
    big = tmp_path / "big.rrd"
    with open(big, "wb") as f:
        f.truncate(2 << 30)  # a 2 GiB sparse file
        f.seek((2 << 30) - 32)
        f.write((done / "recording.rrd").read_bytes()[-32:])
    t0 = time.perf_counter()
    assert "no RRD footer" in recording_fault(big)
    assert time.perf_counter() - t0 < 0.5


@pytest.mark.parametrize("damaged", ["meta.json", "eval.json"])
def test_a_sweep_trial_with_a_damaged_file_counts_as_unfinished(done, tmp_path, damaged):
    """`fastrl sweep --resume` resumes such a trial (rewriting the file) instead of stopping on a traceback."""
    from fastrl.runner.sweep.plan import is_finished

    run = tmp_path / done.name
    shutil.copytree(done, run)
    assert is_finished(run)
    cut(run / damaged)
    assert not is_finished(run)
