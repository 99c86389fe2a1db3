"""Fuzzing pose CSVs: corrupted cells, rows, headers, bytes and timestamps either import or raise PoseError
naming the file; never another exception, never a hang."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fastrl
from fastrl.data import Trajectory
from fastrl.data.poses import COLUMNS, PoseError, import_poses, poses_from_portal
from fastrl.data.replay import expert_trajectories

from ..conftest import spec_file

FUZZ = settings(
    max_examples=100,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
pytestmark = pytest.mark.timeout(120)


@cache
def session():
    """The ImageCentring task and the CSV lines (header first) of a short scripted-expert session."""
    env = fastrl.make(spec_file("imagecentring"), overrides=["episode.time_limit=2"])
    traj = expert_trajectories(env, [0])[0]
    table = poses_from_portal(env.unwrapped.task, traj.time, traj.portal)
    lines = [",".join(COLUMNS)] + [",".join(f"{v:.17g}" for v in row) for row in table]
    return env.unwrapped.task, lines


CELLS = st.sampled_from(
    ["", " ", "nan", "inf", "-inf", "1e9", "1e300", "-1e300", "1e999", "0", "-0", "abc", "1,2", '"', '"1"', "\x00"]
) | st.floats().map(repr)


def check(path, hz) -> None:
    """The property: a trajectory and report, or a PoseError whose first line names the file."""
    task, _ = session()
    try:
        traj, report = import_poses(task, path, {"source": "human"}, resample_hz=hz)
    except PoseError as e:
        assert str(e).startswith(f"{path}") and "\n" not in str(e), str(e)
        return
    assert isinstance(traj, Trajectory) and report
    assert np.isfinite(traj.portal).all() and len(traj.time) <= 1_000_001


@FUZZ
@given(
    edits=st.lists(
        st.tuples(
            st.sampled_from(["cell", "time", "drop", "duplicate", "swap", "header", "extra", "bytes"]),
            st.integers(0, 10**6),
            CELLS,
        ),
        min_size=1,
        max_size=5,
    ),
    hz=st.sampled_from([20.0, None, 1000.0]),
)
def test_mutated_pose_csv(tmp_path_factory, edits, hz):
    """Replace cells and timestamps with extremes, drop, duplicate or swap rows, break the header, add bytes."""
    _, lines = session()
    lines = list(lines)
    raw = b""
    for kind, k, cell in edits:
        row = 1 + k % (len(lines) - 1) if len(lines) > 1 else 0
        cells = lines[row].split(",")
        if kind == "cell":
            cells[k % len(cells)] = cell
            lines[row] = ",".join(cells)
        elif kind == "time":
            lines[row] = ",".join([cell, *cells[1:]])
        elif kind == "drop" and len(lines) > 1:
            del lines[row]
        elif kind == "duplicate":
            lines.insert(row, lines[row])
        elif kind == "swap":
            lines[row], lines[-1] = lines[-1], lines[row]
        elif kind == "header":
            header = lines[0].split(",")
            header[k % len(header)] = cell
            lines[0] = ",".join(header)
        elif kind == "extra":
            lines[row] += "," + cell
        else:
            raw += bytes([k % 256]) * (1 + k % 7)
    path = tmp_path_factory.getbasetemp() / "poses.csv"
    text = "\n".join(lines) + "\n"
    path.write_bytes(text.encode("utf-8", "surrogatepass") + raw)
    check(path, hz)


@FUZZ
@given(scale=st.sampled_from([1e-6, 1e3, 1e9, 1e300, -1.0]), offset=st.sampled_from([0.0, 1e9, 1e300, -1e300]))
def test_rescaled_and_shifted_time_columns(tmp_path_factory, scale, offset):
    """Timestamps in milliseconds, nanoseconds, epochs or absurd units: import or a clear PoseError."""
    _, lines = session()
    rows = [line.split(",") for line in lines[1:]]
    for r in rows:
        r[0] = repr(float(r[0]) * scale + offset)
    path = tmp_path_factory.getbasetemp() / "scaled.csv"
    path.write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")
    check(path, 20.0)
