"""The Rerun recording of a run: a valid .rrd with scene, episodes, curves, summary, layout."""

import math
import subprocess

import numpy as np
import pytest

import fastrl
from fastrl.agents.expert import ScriptedExpert
from fastrl.log import RunRecorder
from fastrl.log.metrics import summary_markdown
from fastrl.log.shapes import hemisphere, viridis
from fastrl.runner.train.evaluate import record_episode, summarize

from ..conftest import spec_file

rc = pytest.importorskip("rerun.chunk")


@pytest.fixture(scope="module")
def run():
    """Two TraceLines episodes of the scripted expert, with the task they ran in."""
    env = fastrl.make(spec_file("tracelines"), width=64, height=64)
    expert = ScriptedExpert(env)
    eps = [record_episode(env, expert.act, seed=s, image_every=10, on_reset=expert.reset) for s in range(2)]
    env.close()
    return env.unwrapped.task, eps


def verify(path) -> str:
    """Output of `rerun rrd verify`; asserts it succeeded."""
    out = subprocess.run(
        ["rerun", "rrd", "verify", str(path)],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0, out.stderr
    return out.stdout + out.stderr


def chunks(path) -> list:
    """Every chunk of the file's recording."""
    return list(rc.RrdReader(path).stream().to_chunks())


def test_full_recording_is_valid_and_complete(tmp_path, run):
    task, eps = run
    path = tmp_path / "run" / "recording.rrd"
    with RunRecorder(path, run_name="test") as rec:
        rec.log_scene(task)
        for i, ep in enumerate(eps):
            rec.log_episode(i, ep, task, fov_deg=task.spec.scope.fov_deg)
        rec.log_training_columns(
            np.array([100, 200, 300]),
            {"loss/value": np.array([1.0, np.nan, 0.5]), "features/shaping": [0.1, None, 0.3]},
        )
        rec.log_training(
            400,
            {
                "loss/value": 0.4,
                "rollout/ep_rew_mean": 2.0,
                "skip_nan": math.nan,
                "skip_none": None,
            },
        )
        rec.log_training(500, {"loss/value": np.float32(0.3)})
        rec.log_summary(summarize(eps))
        rec.send_blueprint(len(eps))
    rec.close()  # closing twice is fine
    assert "1 file verified" in verify(path)

    got = chunks(path)
    paths = {c.entity_path for c in got}
    timelines = set().union(*(c.timeline_names for c in got))
    for expected in [
        "/world",
        "/world/scene/shell",
        "/world/scene/plate",
        "/world/scene/portals",
        "/world/scene/avatars",
        "/world/scene/line",
        "/world/eval/ep_00/camera",
        "/world/eval/ep_00/camera/image",
        "/world/eval/ep_00/shaft",
        "/world/eval/ep_00/trajectory",
        "/world/eval/ep_01/camera",
        "/world/eval/ep_01/avatar",
        "/metrics/eval/ep_00/reward",
        "/metrics/eval/ep_01/features/shaping",
        "/metrics/train/loss/value",
        "/metrics/train/features/shaping",
        "/metrics/train/rollout/ep_rew_mean",
        "/summary",
    ]:
        assert expected in paths, expected
    assert not any("skip_" in p for p in paths)
    assert {"step", "sim_time", "timesteps"} <= timelines
    assert "log_time" not in timelines

    def rows(entity, static=False):
        return sum(c.num_rows for c in got if c.entity_path == entity and c.is_static == static)

    for i, ep in enumerate(eps):
        assert rows(f"/world/eval/ep_{i:02d}/camera") == ep.steps + 1
        assert rows(f"/world/eval/ep_{i:02d}/camera/image") == len(ep.images)
        assert rows(f"/metrics/eval/ep_{i:02d}/reward") == ep.steps + 1
    assert rows("/metrics/train/loss/value") == 4  # 100, 300, 400, 500: the NaN row is dropped
    assert rows("/metrics/train/features/shaping") == 2

    # the camera rotation is the record's wxyz quaternion reordered to xyzw
    cam = next(c for c in got if c.entity_path == "/world/eval/ep_00/camera" and not c.is_static)
    batch = cam.to_record_batch()
    quat = np.array(batch.column("Transform3D:quaternion").to_pylist())[:, 0, :]
    steps = np.array(batch.column("step").to_pylist())
    np.testing.assert_allclose(quat, eps[0].tip_quat[steps][:, [1, 2, 3, 0]], atol=1e-6)

    blueprints = rc.RrdReader(path).blueprints()
    assert len(blueprints) == 1 and blueprints[0].application_id == "fastrl"


def test_scene_only_recording_is_valid(tmp_path, run):
    task, _ = run
    path = tmp_path / "scene.rrd"
    rec = RunRecorder(path)
    rec.log_scene(task)
    rec.close()
    rec.close()
    assert "1 file verified" in verify(path)
    assert {"/world/scene/shell", "/world/scene/line"} <= {c.entity_path for c in chunks(path)}


def test_recordings_in_one_process_are_distinct(tmp_path):
    a, b = RunRecorder(tmp_path / "a.rrd"), RunRecorder(tmp_path / "b.rrd")
    assert a.recording_id != b.recording_id
    a.close(), b.close()
    assert RunRecorder(tmp_path / "c.rrd", recording_id="fixed").recording_id == "fixed"


def test_summary_markdown_has_headline_figures(run):
    _, eps = run
    text = summary_markdown(summarize(eps))
    assert "| episodes | 2 |" in text
    assert "success rate" in text and "shaping" in text and text.count("\n| 1 |") == 1


def test_shell_has_holes_and_outward_triangles():
    verts, _, tris = hemisphere(0.1)
    hole = np.array([1.0, 0.0, 0.0])
    _, _, holed = hemisphere(0.1, [(hole, 0.2)])
    assert len(holed) < len(tris)
    centres = verts[holed].mean(axis=1)
    assert (centres / np.linalg.norm(centres, axis=1, keepdims=True) @ hole < math.cos(0.2)).all()
    a, b, c = (verts[tris[:, k]] for k in range(3))
    # counter-clockwise seen from outside: the normal of (a, b, c) points away from the centre
    assert (np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) > 0).all()
    np.testing.assert_allclose(np.linalg.norm(verts, axis=1), 0.1)


def test_viridis_ramp_ends_and_clipping():
    c = viridis(np.array([-5.0, 0.0, 1.0, 9.0, np.nan]), 0.0, 1.0)
    assert c.shape == (5, 4) and c.dtype == np.uint8
    assert (c[0] == c[1]).all() and (c[2] == c[3]).all() and (c[4] == c[1]).all()
    assert tuple(c[1, :3]) == (68, 1, 84) and tuple(c[2, :3]) == (253, 231, 37)
