"""Hostile pose CSVs and outputs: absurd timestamps, special files, too many rows, -o a folder or not .npz."""

from __future__ import annotations

import os

import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl.data.poses as poses_module
from fastrl.cli import app
from fastrl.data import Trajectory
from fastrl.data.poses import PoseError, import_poses, poses_from_portal, read_pose_csv

from ..conftest import spec_file
from .test_poses import expert, write_csv

pytestmark = pytest.mark.timeout(120)


def session(tmp_path, last_time: float | None = None):
    """The tracelines task and a pose CSV of an expert session, its last timestamp optionally replaced."""
    env, traj = expert("tracelines")
    table = poses_from_portal(env.unwrapped.task, traj.time, traj.portal)
    if last_time is not None:
        table[-1, 0] = last_time
    return env.unwrapped.task, write_csv(tmp_path / "s.csv", table)


@pytest.mark.parametrize("last", [1e9, 1e300])
def test_absurd_timestamps_do_not_explode_the_resampling_grid(tmp_path, last):
    """A timestamp of 1e9 s or 1e300 s: a PoseError naming the span, with or without resampling."""
    task, csv = session(tmp_path, last)
    for hz in (20.0, None):
        with pytest.raises(PoseError) as exc:
            import_poses(task, csv, {}, resample_hz=hz)
        assert str(exc.value).startswith(f"{csv}: the samples span") and "is the time column in seconds?" in str(exc)


def test_cli_reports_absurd_timestamps_in_one_line(tmp_path):
    """Through `fastrl import-poses`: exit 2, the file and the span first, no traceback, nothing written."""
    _, csv = session(tmp_path, 1e9)
    res = CliRunner().invoke(app, ["import-poses", str(spec_file("tracelines")), str(csv)])
    assert res.exit_code == 2 and "Traceback" not in res.output
    assert res.stderr.splitlines()[0].startswith(f"{csv}: the samples span 1e+09 s")
    assert not csv.with_suffix(".npz").exists()


def test_row_limit_and_special_files(tmp_path, monkeypatch):
    """More rows than the limit, a FIFO, a folder: PoseError naming the file, never a hang."""
    _, csv = session(tmp_path)
    monkeypatch.setattr(poses_module, "MAX_POSE_ROWS", 10)
    with pytest.raises(PoseError, match=r"s\.csv:12: more than 10 samples"):
        read_pose_csv(csv)
    os.mkfifo(tmp_path / "fifo.csv")
    (tmp_path / "folder.csv").mkdir()
    for name, why in (("fifo.csv", "not a regular file"), ("folder.csv", "it is a folder")):
        with pytest.raises(PoseError, match=why) as exc:
            read_pose_csv(tmp_path / name)
        assert str(exc.value).startswith(f"{tmp_path / name}: cannot read file")


def test_output_folder_and_output_without_npz(tmp_path):
    """-o an existing folder writes FILE.npz inside it and says so; -o without .npz is exit 2, nothing written."""
    _, csv = session(tmp_path)
    folder = tmp_path / "out"
    folder.mkdir()
    res = CliRunner().invoke(app, ["import-poses", str(spec_file("tracelines")), str(csv), "-o", str(folder)])
    assert res.exit_code == 0, res.output
    assert f"wrote {folder / 's.npz'}" in res.stdout
    assert np.isfinite(Trajectory.load(folder / "s.npz").portal).all()
    res = CliRunner().invoke(app, ["import-poses", str(spec_file("tracelines")), str(csv), "-o", str(tmp_path / "t")])
    assert res.exit_code == 2 and res.stderr.strip() == f"-o {tmp_path / 't'}: a trajectory file name ends in .npz " + (
        "(or give an existing folder)"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "s.csv"]
