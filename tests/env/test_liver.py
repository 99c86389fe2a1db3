"""The liver tour: abdomen scene, anatomy meshes and their errors, landmarks, camera-position state, metrics."""

import json
import math
import subprocess

import gymnasium
import numpy as np
import pytest
import yaml
from rerun.chunk import RrdReader
from scipy.spatial import cKDTree
from typer.testing import CliRunner

import fastrl
from fastrl.agents.expert import run_expert_episode
from fastrl.assess.tour import economy, safety, tour_metrics
from fastrl.cli import app
from fastrl.irl.networks import load_networks
from fastrl.model.kinematics import Kinematics, solve_view, view_residuals
from fastrl.spec import SpecError, load_spec, read_yaml
from fastrl.spec.anatomy import landmark_pose, organ_vertices
from fastrl.spec.reach import portal_point

from ..conftest import spec_file

LIVER = spec_file("liver_tour")


def write_spec(tmp_path, edit) -> str:
    """A copy of the liver-tour spec, changed by edit(data), in tmp_path."""
    data, _ = read_yaml(LIVER)
    edit(data)
    path = tmp_path / "liver.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def world_vertices(u, organ: str) -> np.ndarray:
    """World vertices of an organ's compiled mesh geom."""
    g = u.model.geom(f"organ_{organ}")
    m = int(g.dataid[0])
    verts = u.model.mesh_vert[u.model.mesh_vertadr[m] : u.model.mesh_vertadr[m] + u.model.mesh_vertnum[m]]
    return u.data.geom_xpos[g.id] + verts @ u.data.geom_xmat[g.id].reshape(3, 3).T


def test_the_scene_compiles_with_the_anatomy_where_the_spec_says():
    env = fastrl.make(LIVER)
    env.reset(seed=0)
    u = env.unwrapped
    spec = u.task_spec
    for name, organ in spec.scene.anatomy.items():
        world = world_vertices(u, name)
        lo, hi = world.min(axis=0), world.max(axis=0)
        assert np.allclose(0.5 * (lo + hi), organ.centre, atol=2e-3), name
        assert np.all(hi - lo <= 2 * np.array(organ.size) + 1e-6) and np.all(hi - lo > np.array(organ.size)), name
        assert np.linalg.norm(world, axis=1).max() < spec.scene.radius  # inside the abdominal wall
    assert u.model.geom("posterior_wall").id >= 0
    point = u.task.portal_point
    assert np.linalg.norm(point) == pytest.approx(spec.scene.radius)  # the trocar is in the wall
    assert math.degrees(math.asin(point[2] / spec.scene.radius)) == pytest.approx(72)


def test_the_gym_id_gives_the_camera_position_state_and_the_cue():
    env = gymnasium.make("fastrl/LiverTour-v0")
    obs, _ = env.reset(seed=0)
    u = env.unwrapped
    # the camera position, then the cue (target direction, distance, dwell), portal coordinates, progress, clock
    assert obs.shape == (3 + 3 + 1 + 1 + 5 + 1 + 1,)
    assert np.allclose(obs[:3], u.data.cam_xpos[u.task.camera], atol=1e-6)
    obs, *_ = env.step(5)  # insert
    assert np.allclose(obs[:3], u.data.cam_xpos[u.task.camera], atol=1e-6)


def test_the_laparoscope_pivots_about_the_trocar():
    env = fastrl.make(LIVER)
    u = env.unwrapped
    shaft = u.model.body("scope_shaft").id
    rng = np.random.default_rng(1)
    env.reset(seed=0)
    worst = 0.0
    for _ in range(400):
        _, _, term, trunc, _ = env.step(rng.integers(0, 11))
        tip, axis = u.data.xpos[shaft], u.data.xmat[shaft].reshape(3, 3)[:, 2]
        worst = max(worst, np.linalg.norm(np.cross(u.task.portal_point - tip, axis)))
        if term or trunc:
            env.reset()
    assert worst < 1e-6


def test_landmarks_face_the_trocar_from_their_organ():
    spec = load_spec(LIVER)
    point = portal_point(spec)
    for lm in spec.task.landmarks:
        organ = spec.scene.anatomy[lm.organ]
        pos, fwd, up = landmark_pose(organ, point)
        verts = organ_vertices(organ)
        assert any(np.allclose(pos, v) for v in verts)
        toward = point - verts.mean(axis=0)
        assert (pos - verts.mean(axis=0)) @ toward >= ((verts - verts.mean(axis=0)) @ toward).max() - 1e-12
        assert np.allclose(fwd, (point - pos) / np.linalg.norm(point - pos))
        assert abs(up @ fwd) < 1e-9 and up[2] > 0


def test_a_landmark_is_seen_only_in_view_centred_and_close_enough():
    env = fastrl.make(LIVER)
    u = env.unwrapped
    env.reset(seed=0)
    q, _ = solve_view(Kinematics(u.task), 0, u.portal_coordinates())
    _, _, _, _, info = u.replay_step(q)
    assert info["cue"]["green"] and info["cue"]["centring"] and info["cue"]["distance"]
    _, _, _, _, info = u.replay_step(q + [0.3, 0, 0, 0, 0])  # pivot away: out of view
    assert not info["cue"]["centring"] and not info["cue"]["green"] and info["cue"]["dwell"] == 0
    lo = u.task.ranges[2, 0]
    _, _, _, _, info = u.replay_step(np.array([q[0], q[1], lo, q[3], q[4]]))  # retract: too far
    assert not info["cue"]["distance"] and not info["cue"]["green"]
    need = int(np.ceil(u.task_spec.task.cue.dwell * u.task_spec.episode.control_hz - 1e-9))
    for _ in range(need):
        _, _, _, _, info = u.replay_step(q)
    assert info["subtask"] == 1  # held for the dwell: the next landmark


def test_the_scripted_expert_completes_the_tour():
    env = fastrl.make(LIVER)
    results = [run_expert_episode(env, seed=s) for s in range(4)]
    assert all(r["success"] for r in results)
    assert all(r["time"] < 15 for r in results)


def test_economy_counts_distance_inside_the_cavity_only():
    line = np.column_stack([np.linspace(-0.05, 0.05, 11), np.zeros(11), np.full(11, 0.05)])
    assert economy(line, 0.15) == pytest.approx(0.1)
    outside = line.copy()
    outside[-3:, 2] = -0.01  # the last three samples under the posterior wall
    assert economy(outside, 0.15) == pytest.approx(0.07)
    assert economy(line[:1], 0.15) == 0.0
    still = np.tile([0.0, 0.0, 0.05], (20, 1))
    assert economy(still, 0.15) == 0.0


def test_safety_sums_the_distance_to_the_closest_anatomy_vertex():
    tree = cKDTree(np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]))
    cam = np.array([[0.0, 0.0, 0.02], [0.1, 0.0, 0.03], [0.05, 0.0, 0.0]])
    assert safety(cam, tree) == pytest.approx(0.02 + 0.03 + 0.05)
    assert safety(np.vstack([cam, cam]), tree) == pytest.approx(2 * 0.1)  # a sum: twice the samples, twice
    m = tour_metrics(cam, [0, 2, 0], tree, 0.15)
    assert m["contacts"] == 1 and m["safety"] == pytest.approx(0.1)


def test_a_missing_mesh_file_is_a_spec_error_at_its_line(tmp_path):
    path = write_spec(tmp_path, lambda d: d["scene"]["anatomy"]["left_lobe"].update(mesh="meshes/nope.obj"))
    with pytest.raises(SpecError) as e:
        load_spec(path)
    text = str(e.value)
    assert f"{path}:" in text and "scene.anatomy.left_lobe.mesh" in text and "does not exist" in text
    line = int(text.split(f"{path}:")[1].split(":")[0])
    assert "mesh: meshes/nope.obj" in path.read_text().splitlines()[line - 1]


def test_an_unreadable_mesh_file_is_a_spec_error(tmp_path):
    (tmp_path / "bad.obj").write_text("this is not\nv 1 2\n")
    path = write_spec(tmp_path, lambda d: d["scene"]["anatomy"]["left_lobe"].update(mesh="bad.obj"))
    with pytest.raises(SpecError, match=r"scene\.anatomy\.left_lobe\.mesh: cannot read mesh"):
        load_spec(path)


def _obj(path, verts, faces):
    """Write an OBJ file."""
    path.write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in verts) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
    )


TETRA = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
TETRA_FACES = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


def test_a_mesh_outside_the_cavity_is_a_spec_error(tmp_path):
    _obj(tmp_path / "far.obj", TETRA * 0.05 + [0.12, 0.0, 0.02], TETRA_FACES)
    path = write_spec(tmp_path, lambda d: d["scene"]["anatomy"]["bowel"].update(mesh="far.obj"))
    with pytest.raises(SpecError, match=r"scene\.anatomy\.bowel\.mesh: bowel is outside the cavity"):
        load_spec(path)


def test_a_mesh_file_replaces_the_parametric_organ(tmp_path):
    (tmp_path / "meshes").mkdir()
    _obj(tmp_path / "meshes" / "gb.obj", TETRA * 20 + [30, -60, 10], TETRA_FACES)  # millimetres
    path = write_spec(
        tmp_path, lambda d: d["scene"]["anatomy"]["gallbladder"].update(mesh="meshes/gb.obj", scale=0.001)
    )
    env = fastrl.make(path)
    env.reset(seed=0)
    world = world_vertices(env.unwrapped, "gallbladder")
    assert np.allclose(np.sort(world, axis=0), np.sort(TETRA * 0.02 + [0.03, -0.06, 0.01], axis=0), atol=1e-6)


def test_liver_tour_needs_an_abdomen_and_known_organs(tmp_path):
    path = write_spec(tmp_path, lambda d: d["task"]["landmarks"].append({"organ": "spleen"}))
    with pytest.raises(SpecError, match=r"task\.landmarks\.3\.organ: no organ named 'spleen'"):
        load_spec(path)


def test_the_study_runs_end_to_end_and_resumes_without_redoing(tmp_path):
    runs = tmp_path / "runs"
    args = [
        "run",
        str(LIVER),
        "--runs",
        str(runs),
        "--no-progress",
        "--set",
        "study.levels=2",
        "--set",
        "study.per_level=3",
        "--set",
        "study.best=2",
        "--set",
        "study.timesteps=512",
        "--set",
        "train.n_envs=2",
        "--set",
        "train.ppo.n_steps=128",
        "--set",
        "train.ppo.batch_size=128",
        "--set",
        "evaluate.episodes=1",
    ]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    assert "GAIL" in res.output and "AIRL" in res.output
    (run,) = (runs / "liver_tour").iterdir()
    result = json.loads((run / "experiment.json").read_text())
    assert result["n"] == 6 and len(result["best"]) == 2
    heuristic = sorted((r["heuristic"] for r in result["procedures"]), reverse=True)
    assert sorted(r["heuristic"] for r in result["procedures"] if r["best"]) == sorted(heuristic[:2])
    for algo in ("gail", "airl"):
        for cell in result["table3"][algo].values():
            assert -1 <= cell["rho"] <= 1 and 0 <= cell["p"] <= 1
        saved = {f.name for f in (run / algo / "networks").iterdir()}
        assert saved >= {"reward.safetensors", "value.safetensors", "policy.safetensors"}
        reward = load_networks(run / algo / "networks")._reward.meta  # the policy sees the cue, the reward does not
        assert reward["inputs"] == [0, 1, 2] and reward.get("reward_inputs", [0, 1, 2]) == [0, 1, 2]
        trained = load_spec(run / algo / "spec.yaml")  # the generator starts at the whole cohort's states
        assert trained.irl.demonstrations.others == str(run / "cohort") and trained.generator_recorded_starts == 0.25
    assert len(list((run / "best").glob("*.npz"))) == 2 and len(list((run / "cohort").glob("*.npz"))) == 6
    assert (run / "table3.png").stat().st_size > 10_000
    verify = subprocess.run(
        ["rerun", "rrd", "verify", str(run / "recording.rrd")], capture_output=True, text=True, timeout=120
    )
    assert verify.returncode == 0, verify.stderr
    entities = {str(c.entity_path) for c in RrdReader(str(run / "recording.rrd")).stream()}
    assert {"/figure", "/summary", "/world/scene/anatomy/right_lobe", "/correlations/airl/value_economy"} <= entities
    assert sum(e.startswith("/world/procedures/") and e.count("/") == 4 for e in entities) == 6
    before = {p: p.stat().st_mtime_ns for p in (run / "gail" / "networks").iterdir()}
    (run / "experiment.json").unlink()
    res = CliRunner().invoke(app, ["run", "--resume", str(run), "--no-progress"])
    assert res.exit_code == 0, res.output
    assert json.loads((run / "experiment.json").read_text())["table3"] == result["table3"]
    assert {p: p.stat().st_mtime_ns for p in (run / "gail" / "networks").iterdir()} == before  # not retrained


def test_a_target_behind_the_camera_is_not_centred():
    rot, up = np.eye(3), np.array([0.0, 1.0, 0.0])  # camera looks along -z
    ahead = view_residuals(np.zeros(3), rot, np.array([0.0, 0.0, -0.05]), None, up, 0.05, 0.02)
    behind = view_residuals(np.zeros(3), rot, np.array([0.001, 0.0, 0.05]), None, up, 0.05, 0.02)
    assert abs(ahead[0]) < 1e-9 and abs(ahead[1]) < 1e-9 and abs(ahead[3]) < 1e-9
    assert abs(behind[0]) > math.radians(90) and abs(behind[1]) > math.radians(90)


def test_duplicate_trocar_names_are_a_spec_error(tmp_path):
    first = "    - {name: umbilicus, azimuth: 180"
    text = LIVER.read_text().replace(first, "    - {name: umbilicus, azimuth: 0, elevation: 70}\n" + first)
    path = tmp_path / "dup.yaml"
    path.write_text(text)
    with pytest.raises(SpecError, match=r"dup.yaml:16: scene.portals: portal names must be unique"):
        load_spec(path)
