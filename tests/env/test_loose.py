"""LooseBodies: the grasper holds a body only when its jaws close on it, a body counts once released in the cup."""

import warnings

import gymnasium as gym
import numpy as np
import pytest

import fastrl
from fastrl.agents.expert import run_expert_episode

from ..conftest import spec_file


@pytest.mark.parametrize("mode", ["discrete", "continuous", "rates"])
def test_loose_bodies_pass_both_env_checkers(mode):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make("fastrl/LooseBodies-v0", actions={"mode": mode})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped, skip_render_check=True)
        sb3_check_env(fastrl.make("loose_bodies", actions={"mode": mode}))


@pytest.mark.parametrize("mode", ["discrete", "rates"])
def test_expert_drops_every_body_in_the_cup(mode):
    env = fastrl.make(spec_file("loose_bodies"), actions={"mode": mode})
    result = run_expert_episode(env, seed=2)
    assert result["success"] and result["subtasks"] == 3, result
    u = env.unwrapped
    assert all(u.loose.in_cup(u.data, k) for k in range(3))


def _grasper_at(env, target, jaw):
    """Put the grasper's tip on `target` with the jaw at `jaw` (rad), at rest."""
    from fastrl.model.instruments import aim

    u = env.unwrapped
    t = u.task.instruments[0]
    q = np.zeros(5)
    q[:3], q[4] = aim(t.point, t.rot, target, 0.0), jaw
    u.family.place_instruments(q)


def _close(env, steps=15):
    """Close the jaw at full rate, everything else still."""
    a = np.zeros(env.action_space.shape, np.float32)
    a[-1] = -1.0
    for _ in range(steps):
        _, _, _, _, info = env.step(a)
    return info


def test_jaws_closing_on_a_body_hold_it_and_closing_elsewhere_do_not():
    env = fastrl.make(spec_file("loose_bodies"), actions={"mode": "rates"})
    env.reset(seed=0)
    u = env.unwrapped
    body = u.data.xpos[u.loose.bodies[0]].copy()
    _grasper_at(env, body + np.array([0.0, 0.0, 0.03]), 1.0)  # 3 cm above: nothing to close on
    _close(env)
    assert u.loose.held == -1
    _grasper_at(env, body, 1.0)
    _close(env)
    assert u.loose.held == 0
    a = np.zeros(env.action_space.shape, np.float32)
    a[7] = -1.0  # retract: the body comes along
    for _ in range(10):
        env.step(a)
    assert u.data.xpos[u.loose.bodies[0]][2] > body[2] + 0.005
    assert np.allclose(u.state.target_pos, u.loose.cup)  # held: the cue moves to the cup


def test_a_body_dropped_beside_the_cup_does_not_count():
    env = fastrl.make(spec_file("loose_bodies"), actions={"mode": "rates"})
    env.reset(seed=0)
    u = env.unwrapped
    body = u.data.xpos[u.loose.bodies[0]].copy()
    _grasper_at(env, body, 1.0)
    _close(env)
    a = np.zeros(env.action_space.shape, np.float32)
    a[-1] = 1.0  # open again where it was: released on the plate, not in the cup
    for _ in range(40):
        _, _, _, _, info = env.step(a)
    assert u.loose.held == -1 and not u.loose.in_cup(u.data, 0) and info["subtask"] == 0


def test_grasping_pays_once_per_body_and_the_target_jump_is_not_shaped():
    env = fastrl.make(spec_file("loose_bodies"))
    from fastrl.agents.expert import ScriptedExpert

    expert = ScriptedExpert(env)
    obs, _ = env.reset(seed=1)
    grasps, shaping = [], []
    for _ in range(1200):
        obs, _, term, trunc, info = env.step(expert.act(obs))
        grasps.append(info["features"]["grasp_shaping"])
        shaping.append(info["features"]["tool_shaping"])
        if term or trunc:
            break
    assert info["success"] and grasps.count(1.0) == 3 and sum(grasps) == 0.0
    assert max(np.abs(shaping)) < 1.0  # the tip moves at most a few mm a step: no jump of the target in it


def test_replay_places_the_loose_bodies_and_scores_like_the_episode(tmp_path):
    from fastrl.agents.expert import ScriptedExpert
    from fastrl.data.replay import replay, rollout_trajectory
    from fastrl.data.trajectory import Trajectory

    env = fastrl.make(spec_file("loose_bodies"), actions={"mode": "rates"})
    expert = ScriptedExpert(env)
    traj, observations = rollout_trajectory(env, expert.act, 2, {"source": "expert"}, expert.reset)
    assert traj.bodies.shape == (len(traj.time), 3, 7) and traj.meta["subtasks"] == 3
    loaded = Trajectory.load(traj.save(tmp_path / "t.npz"))
    np.testing.assert_array_equal(loaded.bodies, traj.bodies)
    replayed, infos, _ = replay(fastrl.make(spec_file("loose_bodies"), actions={"mode": "rates"}), loaded)
    np.testing.assert_allclose(replayed, observations, atol=1e-9)
    assert infos[-1]["success"]
    without = Trajectory(loaded.time, loaded.portal, loaded.meta, instruments=loaded.instruments)
    _, infos, _ = replay(fastrl.make(spec_file("loose_bodies"), actions={"mode": "rates"}), without)
    assert infos[-1]["subtask"] == 0  # the bodies' physics is not in the portal coordinates: they stay put


def test_bodies_of_another_task_are_refused(tmp_path):
    from fastrl.data.replay import replay
    from fastrl.data.trajectory import Trajectory, TrajectoryError

    env = fastrl.make(spec_file("loose_bodies"))
    t = np.arange(3) * 0.05
    q = np.tile(env.unwrapped.portal_coordinates(), (3, 1))
    with pytest.raises(TrajectoryError, match=r"bodies has 2 loose bodies per sample, the task 3"):
        replay(env, Trajectory(t, q, {"seed": 0}, bodies=np.zeros((3, 2, 7))))
    with pytest.raises(TrajectoryError, match=r"bodies must have shape \(3, k, 7\)"):
        Trajectory(t, q, {"seed": 0}, bodies=np.zeros((3, 2, 3)))


def test_recording_shows_the_cup_and_the_bodies_moving(tmp_path):
    rc = pytest.importorskip("rerun.chunk")
    from fastrl.agents.expert import ScriptedExpert
    from fastrl.log import RunRecorder
    from fastrl.runner.train.evaluate import record_episode

    env = fastrl.make(spec_file("loose_bodies"), actions={"mode": "rates"}, width=64, height=64)
    expert = ScriptedExpert(env)
    ep = record_episode(env, expert.act, seed=2, image_every=100, on_reset=expert.reset)
    assert ep.bodies.shape == (len(ep.time), 3, 3)
    cup = env.unwrapped.loose.cup
    assert np.hypot(*(ep.bodies[-1, :, :2] - cup[:2]).T).max() < 0.016  # every body ends in the cup
    path = tmp_path / "r.rrd"
    task = env.unwrapped.task
    with RunRecorder(path, run_name="loose") as rec:
        rec.log_scene(task)
        rec.log_episode(0, ep, task, fov_deg=task.spec.scope.fov_deg)
    rows = {}
    for c in rc.RrdReader(path).stream().to_chunks():
        rows[c.entity_path] = rows.get(c.entity_path, 0) + c.num_rows
    assert rows["/world/eval/ep_00/loose_bodies"] == len(ep.time)
    assert rows["/world/scene/cup/floor"] == 1 and rows["/world/scene/cup/wall"] == 1
    env.close()
