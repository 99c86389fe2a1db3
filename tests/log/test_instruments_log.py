"""Instruments on screen: the endoscope image shows the probe, the Rerun recording holds both instruments and paths."""

import numpy as np
import pytest

import fastrl
from fastrl.agents.expert import ScriptedExpert
from fastrl.log import RunRecorder
from fastrl.runner.train.evaluate import record_episode

from ..conftest import spec_file

rc = pytest.importorskip("rerun.chunk")


def _touching(env):
    """Step the expert until the probe touches the first target."""
    expert = ScriptedExpert(env)
    obs, _ = env.reset(seed=0)
    for _ in range(400):
        obs, _, _, _, info = env.step(expert.act(obs))
        if info["cue"]["touching"] and info["cue"]["centring"]:
            return
    raise AssertionError("the expert never touched the target")


def test_endoscope_image_shows_the_probe():
    env = fastrl.make(spec_file("triangulation"), actions={"mode": "rates"}, width=96, height=96)
    _touching(env)
    u = env.unwrapped
    with_probe = u.render().astype(int)
    q = u.instrument_coordinates()
    q[2] = u.task.instruments[0].ranges[2, 0]  # pulled back to the portal: out of the view
    u.family.place_instruments(q)
    without = u.render().astype(int)
    changed = (np.abs(with_probe - without).sum(axis=2) > 60).mean()
    assert changed > 0.005, changed  # the probe's shaft and tip cover part of the image
    env.close()


def test_recording_holds_each_instrument_and_its_path(tmp_path):
    env = fastrl.make(spec_file("triangulation"), actions={"mode": "rates"}, width=64, height=64)
    expert = ScriptedExpert(env)
    ep = record_episode(env, expert.act, seed=1, image_every=50, on_reset=expert.reset)
    task = env.unwrapped.task
    assert ep.tools.shape == (len(ep.time), 1, 2, 3)
    np.testing.assert_allclose(np.linalg.norm(ep.tools[:, 0, 0] - ep.tools[:, 0, 1], axis=1), 0.16, atol=1e-9)
    path = tmp_path / "r.rrd"
    with RunRecorder(path, run_name="instruments") as rec:
        rec.log_scene(task)
        rec.log_episode(0, ep, task, fov_deg=task.spec.scope.fov_deg)
    got = list(rc.RrdReader(path).stream().to_chunks())
    rows = {}
    for c in got:
        rows[c.entity_path] = rows.get(c.entity_path, 0) + c.num_rows
    base = "/world/eval/ep_00"
    assert rows[f"{base}/probe/shaft"] == rows[f"{base}/probe/tip"] == len(ep.time)
    assert rows[f"{base}/probe/path"] == 1 and f"{base}/shaft" in rows
    env.close()
