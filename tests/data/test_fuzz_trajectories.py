"""Fuzzing trajectory files: corrupted bytes, arrays of any shape and dtype, metadata of any JSON shape either load
and replay, or raise TrajectoryError naming the file; never another exception, never a hang."""

from __future__ import annotations

import json
import tempfile
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import fastrl
from fastrl.assess.report import score_files
from fastrl.assess.scoring import Scorer
from fastrl.data import Trajectory, TrajectoryError
from fastrl.data.replay import expert_trajectories, replay

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
def env_and_file():
    """The ImageCentring env, one short scripted-expert trajectory and its .npz bytes."""
    env = fastrl.make(spec_file("imagecentring"), overrides=["episode.time_limit=2"])
    traj = expert_trajectories(env, [0])[0]
    with tempfile.TemporaryDirectory() as folder:
        data = traj.save(Path(folder) / "expert.npz").read_bytes()
    return env, traj, data


def check(env, path) -> None:
    """The property: a file loads and replays (or is refused for its coordinates), or TrajectoryError names it."""
    try:
        traj = Trajectory.load(path)
    except TrajectoryError as e:
        assert str(e).startswith(f"{path}: ") and "\n" not in str(e), str(e)
        return
    try:
        obs, _, rewards = replay(env, traj)
    except TrajectoryError as e:
        assert "outside the portal's range" in str(e), str(e)
        return
    assert np.isfinite(obs).all() and np.isfinite(rewards).all()


@FUZZ
@given(
    edits=st.lists(
        st.tuples(
            st.sampled_from(["flip", "cut", "insert", "zero"]), st.floats(0, 1), st.binary(min_size=1, max_size=8)
        ),
        min_size=1,
        max_size=4,
    )
)
def test_corrupted_bytes(tmp_path_factory, edits):
    """Flip, cut, insert and zero bytes anywhere in a valid .npz."""
    folder = tmp_path_factory.getbasetemp()
    env, _, data = env_and_file()
    data = bytearray(data)
    for kind, where, chunk in edits:
        i = int(where * (len(data) - 1))
        if kind == "flip":
            data[i] ^= chunk[0] or 1
        elif kind == "cut":
            del data[i:]
            if not data:
                data = bytearray(chunk)
        elif kind == "insert":
            data[i:i] = chunk
        else:
            data[i : i + len(chunk)] = bytes(len(chunk))
    path = folder / "corrupt.npz"
    path.write_bytes(bytes(data))
    check(env, path)


DTYPES = st.sampled_from(["<f8", "<f4", "<f2", "<i8", "<u1", "|b1", "<c16", "<U4", "|S3", "<M8[s]", "<m8[s]"])
SPECIAL = st.sampled_from([0.0, -0.0, 1e300, -1e300, 1e9, 100.0, -1.0, np.nan, np.inf, -np.inf, 5e-324])


JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-(2**70), 2**70) | st.floats() | st.text(max_size=5),
    lambda c: st.lists(c, max_size=3) | st.dictionaries(st.text(max_size=4), c, max_size=3),
    max_leaves=20,
)
META_KEYS = st.sampled_from(["seed", "skill", "subject", "spec", "task_hash", "source", "subtasks", "x"])


@FUZZ
@given(
    which=st.sampled_from(["time", "portal", "actions", "meta", "coords"]),
    shape=hnp.array_shapes(min_dims=0, max_dims=3, max_side=6),
    data=st.data(),
)
def test_arrays_of_any_shape_and_dtype(tmp_path_factory, which, shape, data):
    """Replace one array with any shape and dtype, one coordinate column with extremes, or meta with any JSON."""
    folder = tmp_path_factory.getbasetemp()
    env, traj, _ = env_and_file()
    arrays_ = {
        "time": traj.time,
        "portal": traj.portal,
        "actions": traj.actions,
        "meta": np.array(json.dumps(traj.meta)),
    }
    if which == "meta":
        meta = {**traj.meta, **data.draw(st.dictionaries(META_KEYS, JSON, max_size=3))}
        arrays_["meta"] = np.array(json.dumps(meta))
    elif which == "coords":
        portal = traj.portal.copy()
        rows = data.draw(st.lists(st.integers(0, len(portal) - 1), min_size=1, max_size=3))
        portal[rows, data.draw(st.integers(0, 4))] = data.draw(SPECIAL | st.floats(-10, 10))
        arrays_["portal"] = portal
    else:
        arrays_[which] = data.draw(hnp.arrays(data.draw(DTYPES), shape))
    path = folder / "arrays.npz"
    np.savez(path, **arrays_)
    check(env, path)


def test_a_batch_of_fuzzed_files_is_scored_file_by_file(tmp_path):
    """score_files over good and corrupted files: every file is either scored or named in one problem line."""
    env, traj, data = env_and_file()
    files = []
    rng = np.random.default_rng(0)
    for k in range(12):
        corrupt = bytearray(data)
        for i in rng.integers(0, len(corrupt), size=k):
            corrupt[i] ^= 0xFF
        files.append(tmp_path / f"f{k:02d}.npz")
        files[-1].write_bytes(bytes(corrupt))
    scored, problems = score_files(Scorer(env.unwrapped.task_spec), files)
    assert len(scored) + len(problems) == len(files) and scored
    named = {f for f in files for p in problems if p.startswith(f"{f}: ")}
    assert len(named) == len(problems)
