"""Hostile trajectory files: impossible coordinates, complex numbers, wrong metadata types, deep JSON, FIFOs and
decompression bombs are refused naming the file and the problem; in a batch the others are still processed."""

from __future__ import annotations

import io
import json
import os
import zipfile
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.data import Trajectory, TrajectoryError, load_trajectories
from fastrl.data.replay import expert_trajectories, replay
from fastrl.runner.study import write_cohort
from fastrl.runner.train.learner import demonstrations
from fastrl.spec import load_spec

from ..conftest import spec_file

pytestmark = pytest.mark.timeout(120)


@cache
def expert():
    """The TraceLines env and one scripted-expert trajectory on it."""
    env = fastrl.make(spec_file("tracelines"))
    return env, expert_trajectories(env, [0])[0]


def write(path: Path, traj: Trajectory, **arrays) -> Path:
    """Save a trajectory, then overwrite some of its arrays (any dtype, any meta text) with raw numpy."""
    data = {"time": traj.time, "portal": traj.portal, "meta": np.array(json.dumps(traj.meta)), "actions": traj.actions}
    data.update(arrays)
    np.savez(path, **{k: v for k, v in data.items() if v is not None})
    return path


def with_coordinate(portal: np.ndarray, column: int, value) -> np.ndarray:
    """A copy of portal coordinates with one column of the middle sample set to value."""
    out = portal.astype(np.result_type(portal, type(value)), copy=True)
    out[len(out) // 2, column] = value
    return out


IMPOSSIBLE = [
    ("pitch_1e9", 0, 1e9, "pitch = 1e+09 rad at sample", "[-1.047, 1.047] rad"),
    ("insertion_100m", 2, 100.0, "insertion = 100 m at sample", "[0.01, 0.15] m"),
    ("insertion_negative", 2, -0.05, "insertion = -0.05 m at sample", "[0.01, 0.15] m"),
    ("roll_1e300", 3, 1e300, "roll = 1e+300 rad at sample", "[-3.142, 3.142] rad"),
]


@pytest.mark.parametrize(("name", "column", "value", "what", "range_"), IMPOSSIBLE, ids=[c[0] for c in IMPOSSIBLE])
def test_impossible_coordinates_are_refused_naming_coordinate_value_and_range(
    tmp_path, name, column, value, what, range_
):
    """Replay refuses a trajectory the portal cannot reach instead of clipping and scoring it."""
    env, traj = expert()
    bad = Trajectory.load(write(tmp_path / f"{name}.npz", traj, portal=with_coordinate(traj.portal, column, value)))
    with pytest.raises(TrajectoryError) as exc:
        replay(env, bad)
    assert what in str(exc.value) and f"outside the portal's range {range_}" in str(exc.value)


def test_everything_1e300_and_complex_numbers_are_refused(tmp_path):
    """1e300 everywhere is out of range; complex coordinates are not real numbers (never silently cast)."""
    env, traj = expert()
    huge = Trajectory.load(write(tmp_path / "huge.npz", traj, portal=np.full_like(traj.portal, 1e300)))
    n = len(traj.time)
    with pytest.raises(TrajectoryError, match=rf"pitch = 1e\+300 rad at sample 0 .*; {n} of {n} samples are out"):
        replay(env, huge)
    for name, arrays in [
        ("complex_portal", {"portal": traj.portal + 1j}),
        ("complex_time", {"time": traj.time.astype(complex)}),
        ("text_time", {"time": traj.time.astype(str)}),
        ("complex_actions", {"actions": traj.actions + 0j}),
    ]:
        with pytest.raises(TrajectoryError, match=f"{name}.npz: .*must hold real numbers, got dtype"):
            Trajectory.load(write(tmp_path / f"{name}.npz", traj, **arrays))


@pytest.mark.parametrize(
    ("time", "why"),
    [
        (np.arange(5) * 1e300, "time spans 4e+300 s, more than a day (86,400 s): is it in seconds?"),
        (np.arange(5) * 1e-300, "samples 0 and 1 are 1e-300 s apart, less than 1e-06 s: is time in seconds?"),
        (
            np.array([0.0, 0.05, 0.1, 1e9, 1e9 + 0.05]),
            "time spans 1e+09 s, more than a day (86,400 s): is it in seconds?",
        ),
    ],
    ids=["span_1e300", "step_1e-300", "span_1e9"],
)
def test_implausible_time_columns_are_refused(time, why):
    """Times must be plausible seconds: scores (duration, smoothness) of 1e300 s would be inf, not a score."""
    with pytest.raises(TrajectoryError) as exc:
        Trajectory(time, np.zeros((5, 5)), {})
    assert str(exc.value) == why


def nested(depth: int) -> str:
    """A JSON object nested depth levels deep."""
    return '{"a": ' * depth + "1" + "}" * depth


META = [
    ("seed_null", {"seed": None}, "meta.seed must be a whole number from 0 to 2^63 - 1, got null"),
    ("seed_negative", {"seed": -3}, "meta.seed must be a whole number from 0 to 2^63 - 1, got -3"),
    ("seed_mapping", {"seed": {"a": 1}}, "meta.seed must be a whole number from 0 to 2^63 - 1, got a mapping"),
    ("seed_fraction", {"seed": 1.5}, "got 1.5"),
    ("seed_bool", {"seed": True}, "got True"),
    ("seed_huge", {"seed": 2**80}, "meta.seed must be a whole number"),
    ("skill_mapping", {"skill": {"level": 3}}, "meta.skill must be a number or a text label, got a mapping"),
    ("skill_list", {"skill": [1, 2]}, "meta.skill must be a number or a text label, got a list"),
    ("subject_list", {"subject": ["a"]}, "meta.subject must be a text or a whole number, got a list"),
    ("task_hash_number", {"task_hash": 5}, "meta.task_hash must be a text, got 5"),
]


@pytest.mark.parametrize(("name", "change", "why"), META, ids=[m[0] for m in META])
def test_metadata_of_the_wrong_type_is_a_clear_error_for_that_file(tmp_path, name, change, why):
    """Each wrong-typed metadata field is named with what was expected and what the file holds."""
    _, traj = expert()
    path = write(tmp_path / f"{name}.npz", traj, meta=np.array(json.dumps({**traj.meta, **change})))
    with pytest.raises(TrajectoryError) as exc:
        Trajectory.load(path)
    assert str(exc.value).startswith(f"{path}: ") and why in str(exc.value)


@pytest.mark.parametrize(
    ("meta", "why"),
    [
        (np.array(nested(100_000)), "nested more than 32 levels deep"),
        (np.array(nested(40)), "nested more than 32 levels deep"),
        (np.array("[1, 2]"), "meta must be a JSON object, got list"),
        (np.array("{"), "meta is not valid JSON"),
        (np.arange(3.0), "meta must be one JSON text"),
        (np.array("x" * 1_000_001), "at most 1,000,000 are read"),
    ],
    ids=["json_100k_deep", "json_40_deep", "json_list", "json_broken", "meta_numbers", "meta_huge"],
)
def test_malformed_metadata_json_is_refused(tmp_path, meta, why):
    """Deep, broken, oversized or non-object metadata JSON: one TrajectoryError, no RecursionError."""
    _, traj = expert()
    with pytest.raises(TrajectoryError, match="meta") as exc:
        Trajectory.load(write(tmp_path / "m.npz", traj, meta=meta))
    assert why in str(exc.value)


def test_special_files_and_bombs_do_not_hang_or_exhaust_memory(tmp_path):
    """A FIFO, a folder and a symlink loop named .npz, a member declaring 10^12 rows, a non-.npy member."""
    _, traj = expert()
    os.mkfifo(tmp_path / "fifo.npz")
    (tmp_path / "folder.npz").mkdir()
    os.symlink(tmp_path / "loop.npz", tmp_path / "loop.npz")
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (10**12, 5)})
    with zipfile.ZipFile(tmp_path / "bomb.npz", "w") as zf:
        zf.writestr("portal.npy", header.getvalue())
        zf.writestr("time.npy", header.getvalue())
        zf.writestr("meta.npy", b"{}")
    cases = {
        "fifo.npz": "not a regular file",
        "folder.npz": "it is a folder",
        "loop.npz": "cannot read file",
        "bomb.npz": "declares shape (1000000000000, 5)",
    }
    for name, why in cases.items():
        with pytest.raises(TrajectoryError) as exc:
            Trajectory.load(tmp_path / name)
        assert str(exc.value).startswith(f"{tmp_path / name}: ") and why in str(exc.value), exc.value


def bad_folder(tmp_path: Path) -> tuple[Path, dict[str, str]]:
    """A folder with one good trajectory and one bad file of each kind; file name -> phrase of its message."""
    env, traj = expert()
    folder = tmp_path / "mixed"
    folder.mkdir()
    traj.save(folder / "a_good.npz")
    write(folder / "pitch.npz", traj, portal=with_coordinate(traj.portal, 0, 1e9))
    write(folder / "seed.npz", traj, meta=np.array(json.dumps({**traj.meta, "seed": None})))
    write(folder / "deep.npz", traj, meta=np.array(nested(100_000)))
    os.mkfifo(folder / "fifo.npz")
    (folder / "junk.npz").write_bytes(b"\x00" * 100)
    return folder, {
        "pitch.npz": "pitch = 1e+09 rad",
        "seed.npz": "meta.seed",
        "deep.npz": "nested more than",
        "fifo.npz": "not a regular file",
        "junk.npz": "not a .npz archive",
    }


def assert_each_named(messages: list[str], folder: Path, expected: dict[str, str]) -> None:
    """One message per bad file, naming it and its problem."""
    assert len(messages) == len(expected), messages
    for name, phrase in expected.items():
        [msg] = [m for m in messages if str(folder / name) in m]
        assert phrase in msg, msg


def test_score_names_and_skips_each_bad_file_and_scores_the_rest(tmp_path):
    """`fastrl score` on a folder: exit 0, every bad file skipped by name, the good one scored (-o a folder)."""
    folder, expected = bad_folder(tmp_path)
    (tmp_path / "out").mkdir()
    out = tmp_path / "out" / "scores.json"
    args = ["score", str(folder), "--spec", str(spec_file("tracelines")), "-o", str(out.parent)]
    res = CliRunner().invoke(app, [*args, "--references", "1", "--no-pictures", "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "Traceback" not in res.output and "scored 1 trajectories" in res.stdout
    assert_each_named(json.loads(out.read_text())["problems"], folder, expected)
    skipped = [line for line in res.stderr.splitlines() if line.startswith("skipped ")]
    assert len(skipped) == len(expected)


def test_demonstrations_and_cohort_loading_skip_bad_files(tmp_path):
    """`fastrl irl --demos DIR` and a study's cohort: bad files named on the console, the rest used."""
    folder, expected = bad_folder(tmp_path)
    console = Console(file=io.StringIO(), width=400)
    spec = load_spec(spec_file("tracelines"), [f"irl.demonstrations.path={folder}", "irl.algorithm=bc"])
    demos = demonstrations(spec, tmp_path / "run", console, progress=False)
    assert len(demos) == 1
    assert_each_named([line for line in console.file.getvalue().splitlines() if "skipped" in line], folder, expected)
    good, errors = load_trajectories([folder])  # without the portal's ranges: only the pitch file loads too
    assert len(good) == 2 and len(errors) == len(expected) - 1
    console = Console(file=io.StringIO(), width=400)
    spec = load_spec(spec_file("tracelines"), ["study.levels=2", "study.per_level=3", "study.best=1"])
    cohort = write_cohort(spec, folder, console, progress=False)
    assert [name for name, _ in cohort] == ["a_good"]
    assert_each_named(console.file.getvalue().splitlines(), folder, expected)
