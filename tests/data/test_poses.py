"""Pose import: forward and inverse portal kinematics, rejection of inconsistent samples, the CLI."""

from functools import cache

import mujoco
import numpy as np
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.data import Trajectory
from fastrl.data.instrument_poses import instrument_columns
from fastrl.data.poses import COLUMNS, PoseError, import_poses, portal_from_poses, poses_from_portal
from fastrl.data.replay import expert_trajectories, replay
from fastrl.model.portal import quat_to_mat, wrap

from ..conftest import spec_file


@cache
def expert(name: str):
    """An env of a bundled spec and one scripted-expert trajectory on it (seed 3)."""
    env = fastrl.make(spec_file(name))
    return env, expert_trajectories(env, [3])[0]


def write_csv(path, poses):
    """A pose CSV as a tracker export would look, written with plain numpy."""
    np.savetxt(path, poses, delimiter=",", header=",".join(COLUMNS), comments="", fmt="%.17g")
    return path


def portal_error(a, b):
    """Largest difference per portal coordinate, angles roll and cable compared modulo 2 pi."""
    d = np.abs(a - b)
    d[:, 3:] = np.abs(wrap(a[:, 3:] - b[:, 3:]))
    return d.max(axis=0)


def test_forward_poses_match_mujoco(task_name):
    env, traj = expert(task_name)
    task = env.unwrapped.task
    poses = poses_from_portal(task, traj.time, traj.portal)
    d, shaft = mujoco.MjData(task.model), task.model.body("scope_shaft").id
    for i in (0, len(traj.time) // 2, -1):
        d.qpos[task.qadr], d.qpos[task.lens_qadr] = traj.portal[i], -traj.portal[i, 4]
        mujoco.mj_kinematics(task.model, d)
        mujoco.mj_camlight(task.model, d)
        np.testing.assert_allclose(poses[i, 1:4], d.cam_xpos[task.camera], atol=1e-12)  # the tip is the camera
        np.testing.assert_allclose(quat_to_mat(poses[[i], 4:8])[0], d.xmat[shaft].reshape(3, 3), atol=1e-12)


def test_inverse_recovers_replayed_portal_coordinates(task_name):
    env, traj = expert(task_name)
    task = env.unwrapped.task
    time, portal, report = portal_from_poses(task, poses_from_portal(task, traj.time, traj.portal))
    assert report.kept == report.rows == len(traj.time) and not report.rejected
    np.testing.assert_array_equal(time, traj.time)
    inside = np.clip(traj.portal[:, :3], task.ranges[:3, 0], task.ranges[:3, 1])
    assert np.all(portal_error(portal, np.column_stack([inside, traj.portal[:, 3:]])) < 1e-9)


def tilt(quat, angle):
    """A quaternion turned by angle about its own x axis (the shaft axis tilts)."""
    w, x, y, z = quat
    c, s = np.cos(angle / 2), np.sin(angle / 2)
    return np.array([w * c - x * s, w * s + x * c, y * c + z * s, z * c - y * s])


def test_inconsistent_samples_are_rejected_with_their_reason():
    env, traj = expert("tracelines")
    task = env.unwrapped.task
    poses = poses_from_portal(task, traj.time, traj.portal)
    side = quat_to_mat(poses[10:11, 4:8])[0][:, 0]
    poses[10, 1:4] += 0.003 * side  # tip 3 mm off the shaft line: axis misses the portal
    poses[20, 4:8] = tilt(poses[20, 4:8], np.radians(10))  # orientation tilted 10 degrees
    poses[30, 5] = np.nan  # tracking dropout
    poses[40, 0] = poses[38, 0]  # time goes back
    poses[50, 4:8] *= 1.1  # not a rotation
    axis = quat_to_mat(poses[60:61, 4:8])[0][:, 2]
    poses[60, 1:4] = task.portal_point + 0.155 * axis  # deeper than the insertion range
    time, portal, report = portal_from_poses(task, poses)
    r = report.rejected
    assert (r["misses_portal"], r["axis_angle"]) == ([10, 20], [20])  # a 10 degree tilt also misses the portal
    assert (r["non_finite"], r["time"], r["quaternion"], r["out_of_range"]) == ([30], [40], [50], [60])
    keep = np.setdiff1d(np.arange(len(traj.time)), [10, 20, 30, 40, 50, 60])
    assert report.kept == len(keep) and np.array_equal(time, traj.time[keep])
    assert np.all(portal_error(portal, traj.portal[keep]) < 1e-9)
    assert any("6 rejected" in line for line in report.lines())
    with pytest.raises(PoseError, match="rejected"):
        portal_from_poses(task, poses, max_rejected=0.01)


def test_imported_trajectory_replays_to_the_same_cue_events(tmp_path):
    env, traj = expert("imagecentring")
    task = env.unwrapped.task
    t60 = np.arange(3 * len(traj.time) - 2) / 60.0  # a 60 Hz tracker; the task steps at 20 Hz
    q60 = np.column_stack([np.interp(t60, traj.time, traj.portal[:, j]) for j in range(5)])
    csv = write_csv(tmp_path / "session.csv", poses_from_portal(task, t60 + 12.5, q60))
    imported, report = import_poses(task, csv, {"seed": 3, "subject": "s01"}, resample_hz=task.spec.episode.control_hz)
    assert len(imported.time) == len(traj.time) and imported.meta["time_offset"] == pytest.approx(12.5)
    assert np.all(portal_error(imported.portal, traj.portal) < 1e-9) and "at 20 Hz" in report[-1]
    _, original, _ = replay(env, traj)
    _, again, _ = replay(env, Trajectory.load(imported.save(tmp_path / "session.npz")))
    events = lambda infos: [(i["subtask"], i["cue"]["green"]) for i in infos]  # noqa: E731
    assert events(again) == events(original) and again[-1]["success"]


def test_cli_writes_a_loadable_trajectory_and_names_broken_files(tmp_path):
    env, traj = expert("tracelines")
    poses = poses_from_portal(env.unwrapped.task, traj.time, traj.portal)
    poses[5, 1] += 0.01
    csv = write_csv(tmp_path / "s.csv", poses)
    res = CliRunner().invoke(
        app,
        [
            "import-poses",
            str(spec_file("tracelines")),
            str(csv),
            "-o",
            str(tmp_path / "out.npz"),
            "--subject",
            "s01",
            "--skill",
            "novice",
        ],
    )
    assert res.exit_code == 0, res.output
    assert "1 rejected" in res.output and "misses_portal" in res.output and "lines 7" in res.output
    t = Trajectory.load(tmp_path / "out.npz")
    assert (t.meta["subject"], t.meta["skill"], t.meta["source"], t.meta["rejected"]) == ("s01", "novice", "human", 1)
    assert t.meta["spec"] == "tracelines" and t.meta["imported_from"] == "s.csv"
    (tmp_path / "cols.csv").write_text("\ufefftime,x,y,z,qw,qx,qy\n0,0,0,0,1,0,0\n")  # with a byte-order mark
    (tmp_path / "cell.csv").write_text(",".join(COLUMNS) + "\n0,0,0,0,1,0,0,0,0\n0.1,0,0,zero,1,0,0,0,0\n")
    for name, why in (
        ("cols.csv", "missing columns ['qz', 'cable']"),
        ("cell.csv", "cell.csv:3: column 'z'"),
        ("none.csv", "cannot read"),
    ):
        res = CliRunner().invoke(app, ["import-poses", str(spec_file("tracelines")), str(tmp_path / name)])
        assert res.exit_code == 2 and name in res.output and why in res.output, res.output
        assert "Traceback" not in res.output


@pytest.mark.parametrize("name", ["triangulation", "loose_bodies"])
def test_tracked_instruments_import_beside_the_scope(tmp_path, name):
    env, traj = expert(name)
    task = env.unwrapped.task
    cols = instrument_columns(task)
    table = poses_from_portal(task, traj.time, traj.portal, traj.instruments)
    shaft = mujoco.MjData(task.model)
    for inst, start in zip(task.instruments, np.cumsum([0] + [len(i.qadr) for i in task.instruments])):
        shaft.qpos[inst.qadr] = traj.instruments[-1, start : start + len(inst.qadr)]
    mujoco.mj_kinematics(task.model, shaft)
    first = task.instruments[0]
    np.testing.assert_allclose(table[-1, 9:12], shaft.xpos[first.tip_body], atol=1e-12)  # the tracked shaft end
    bad = table.copy()
    bad[5, 9 + 3 : 9 + 7] = [2.0, 0.0, 0.0, 0.0]  # one sample's instrument quaternion is not a rotation
    path = tmp_path / "session.csv"
    np.savetxt(path, bad, delimiter=",", header=",".join([*COLUMNS, *cols]), comments="", fmt="%.17g")
    got, report = import_poses(task, path, {"source": "human"})
    assert any("quaternion" in line and "lines 7" in line for line in report), report
    assert any(line.endswith("tracked") for line in report)
    keep = np.delete(np.arange(len(traj.time)), 5)
    ranges = np.concatenate([i.ranges for i in task.instruments])
    inside = np.clip(traj.instruments[keep], ranges[:, 0], ranges[:, 1])  # a jaw a little past its soft limit
    np.testing.assert_allclose(got.instruments, inside, atol=1e-9)
    obs, _, _ = replay(env, got)  # replays with scope and instrument where they were
    assert len(obs) == len(keep)
    np.savetxt(path, table[:, :-1], delimiter=",", header=",".join([*COLUMNS, *cols[:-1]]), comments="", fmt="%.17g")
    with pytest.raises(PoseError, match=f"missing instrument columns \\['{cols[-1]}'\\]"):
        import_poses(task, path, {})
    scope_only = write_csv(tmp_path / "scope.csv", table[:, :9])
    got, report = import_poses(task, scope_only, {})
    assert got.instruments is None and any("not in the file" in line for line in report)
