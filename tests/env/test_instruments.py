"""Instruments in the spec language, the triangulation task, its expert, actions and checkers."""

import warnings

import gymnasium as gym
import numpy as np
import pytest

import fastrl
from fastrl.agents.expert import ScriptedExpert, run_expert_episode
from fastrl.spec import SpecError, load_spec, spec_hash, task_hash

from ..conftest import spec_file

MODES = ["discrete", "continuous", "rates"]


@pytest.mark.parametrize("mode", MODES)
def test_triangulation_passes_both_env_checkers(mode):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make("fastrl/Triangulation-v0", actions={"mode": mode})
    scope = {"discrete": 11, "continuous": 7, "rates": 5}[mode]
    n = env.action_space.n - scope if mode == "discrete" else env.action_space.shape[0] - scope
    assert n == (8 if mode == "discrete" else 4)  # the probe's pitch, yaw, insertion, roll (+/- when discrete)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped, skip_render_check=True)
        sb3_check_env(fastrl.make("triangulation", actions={"mode": mode}))


@pytest.mark.parametrize("mode", MODES)
def test_expert_completes_every_triangulation_target(mode):
    env = fastrl.make(spec_file("triangulation"), actions={"mode": mode})
    for seed in (0, 1):
        result = run_expert_episode(env, seed=seed)
        assert result["success"] and result["subtasks"] == 5, result


def test_a_subtask_needs_the_probe_on_the_target_not_only_the_view():
    env = fastrl.make(spec_file("triangulation"), actions={"mode": "rates"})
    expert = ScriptedExpert(env)
    obs, info = env.reset(seed=0)
    scope_only = np.zeros(env.action_space.shape, np.float32)
    for _ in range(200):  # the scope alone centres the target: never complete without the probe
        a = expert.act(obs)
        scope_only[:5] = a[:5]
        obs, _, _, _, info = env.step(scope_only)
    assert info["cue"]["centring"] and info["cue"]["distance"] and not info["cue"]["touching"]
    assert info["subtask"] == 0 and not info["cue"]["green"]
    for _ in range(200):
        obs, _, _, _, info = env.step(expert.act(obs))
        if info["subtask"]:
            break
    assert info["subtask"] == 1


def test_probe_tip_collides_with_the_plate():
    from fastrl.model.instruments import aim

    env = fastrl.make(spec_file("triangulation"), actions={"mode": "rates"})
    env.reset(seed=0)
    u = env.unwrapped
    t = u.task.instruments[0]
    q = np.zeros(4)
    q[:3] = aim(t.point, t.rot, np.array([0.03, 0.03, 0.0]), 0.01)  # 1 cm short of a plate point, aimed at it
    u.family.place_instruments(q)
    push = np.zeros(env.action_space.shape, np.float32)
    push[7] = 1.0  # the probe's insertion, at full rate: 8 cm more over 2 s
    for _ in range(40):
        _, _, _, _, info = env.step(push)
    assert u.data.xpos[t.tip_body][2] > 0.0  # held on the plate by the contact, not through it
    assert info["contacts"] >= 1 and u.state.instrument_contacts >= 1 and info["features"]["tool_contact"] == 1.0


def test_observation_holds_the_probe_tip_and_its_target_vector():
    env = fastrl.make(spec_file("triangulation"))
    obs, _ = env.reset(seed=3)
    s = env.unwrapped.state
    names = env.unwrapped.task_spec.observation.terms()
    assert {"tool_tip_pos", "tool_tip_quat", "tool_tip_vel", "tool_to_target"} <= set(names)
    np.testing.assert_allclose(np.add(s.instrument_pos, s.instrument_to_target), s.target_pos, atol=1e-12)
    assert obs.shape == env.observation_space.shape


def two_instrument_spec():
    """Triangulation with a grasper through the superior portal beside the probe, every tool term observed."""
    from fastrl.spec.models import TaskSpec

    d = load_spec(spec_file("triangulation")).model_dump()
    d["instruments"].append({"name": "grasper", "kind": "grasper", "portal": "superior", "start": {"insertion": 0.04}})
    d["observation"]["extra"] = [*d["observation"]["extra"], "tool_visible", "tool_portal"]
    return TaskSpec.model_validate(d)


def test_observation_holds_every_instruments_tip_velocity_and_target_vector():
    spec = two_instrument_spec()
    env = fastrl.make(spec, actions={"mode": "rates"})
    one = fastrl.make(spec_file("triangulation"), actions={"mode": "rates"})
    per_tool = 3 + 4 + 3 + 3 + 1 + 1  # tip position, quaternion, velocity, to target, touching, visible
    assert env.observation_space.shape[0] == one.observation_space.shape[0] + per_tool + 1 + 9
    obs, _ = env.reset(seed=2)
    u = env.unwrapped
    act = np.zeros(env.action_space.shape, np.float32)
    act[-5:] = [0.5, -0.5, 0.5, 0.0, 1.0]  # the grasper pivots, goes in, opens its jaw
    for _ in range(6):
        before = [u.data.xpos[t.tip_body].copy() for t in u.task.instruments]
        obs, *_ = env.step(act)
    names = spec.observation.terms()
    from fastrl.terms import OBSERVATION_TERMS

    widths = [OBSERVATION_TERMS[n].width([4, 5]) for n in names]
    cols = dict(zip(names, np.split(obs, np.cumsum(widths)[:-1])))
    for i, t in enumerate(u.task.instruments):
        tip = u.data.xpos[t.tip_body]
        np.testing.assert_allclose(cols["tool_tip_pos"][3 * i : 3 * i + 3], tip, atol=1e-6)
        np.testing.assert_allclose(cols["tool_to_target"][3 * i : 3 * i + 3], u.state.target_pos - tip, atol=1e-6)
        np.testing.assert_allclose(cols["tool_tip_vel"][3 * i : 3 * i + 3], (tip - before[i]) / u.dt, atol=1e-5)
    assert np.linalg.norm(cols["tool_tip_vel"][3:]) > 0.01 and np.abs(cols["tool_portal"]).max() <= 1.0
    jaw = u.data.qpos[u.task.instruments[1].qadr[4]]
    assert cols["tool_portal"][-1] == pytest.approx(2 * jaw / np.radians(60) - 1, abs=1e-5)  # the jaw, observed


def test_instrument_terms_need_an_instrument():
    with pytest.raises(SpecError, match=r"observation.extra.0: 'tool_tip_pos' observes the instruments"):
        load_spec(spec_file("tracelines"), ["observation.extra=[tool_tip_pos]"])
    for field, set_ in (  # the scope's families keep no instrument state: a term of one is refused at load
        ("reward.features.tool_touch", "reward.features.tool_touch={weight: 1.0}"),
        ("observation.extra.0", "observation.extra=[tool_holding]"),
    ):
        with pytest.raises(SpecError, match=field):
            load_spec(spec_file("tracelines"), [set_])
    assert "tool_touch" in load_spec(spec_file("triangulation")).reward.features


def test_instrument_errors_name_their_field(tmp_path):
    spec = spec_file("triangulation")
    with pytest.raises(SpecError, match=r"instruments.0.portal: portal 'lateral' is taken by the scope"):
        load_spec(spec, ["instruments.0.portal=lateral"])
    with pytest.raises(SpecError, match=r"no portal named 'nowhere'"):
        load_spec(spec, ["instruments.0.portal=nowhere"])
    with pytest.raises(SpecError, match=r"triangulation needs an instrument of kind 'probe'"):
        load_spec(spec, ["instruments=[]"])


def test_instruments_enter_the_hashes():
    a = load_spec(spec_file("triangulation"))
    b = load_spec(spec_file("triangulation"), ["instruments.0.touch=0.005"])
    assert task_hash(a) != task_hash(b) and spec_hash(a) != spec_hash(b)


def test_triangulation_trajectories_keep_the_probe_and_replay_identically(tmp_path):
    from fastrl.data.replay import replay, rollout_trajectory
    from fastrl.data.trajectory import Trajectory

    env = fastrl.make(spec_file("triangulation"))
    expert = ScriptedExpert(env)
    traj, observations = rollout_trajectory(env, expert.act, 4, {"source": "expert"}, expert.reset)
    assert traj.instruments.shape == (len(traj.time), 4)
    assert np.ptp(traj.instruments[:, 2]) > 0.02  # the probe went in and out
    loaded = Trajectory.load(traj.save(tmp_path / "t.npz"))
    np.testing.assert_array_equal(loaded.instruments, traj.instruments)
    replayed, infos, _ = replay(fastrl.make(spec_file("triangulation")), loaded)
    np.testing.assert_allclose(replayed, observations, atol=1e-9)
    assert infos[-1]["success"]
    scope_only = Trajectory(loaded.time, loaded.portal, loaded.meta)  # a file from before instruments: still loads
    _, infos, _ = replay(
        fastrl.make(spec_file("triangulation")), Trajectory.load(scope_only.save(tmp_path / "old.npz"))
    )
    assert not infos[-1]["success"]  # the probe stays at its start: the view alone completes nothing


def test_a_cohort_with_instruments_ranks_by_level():
    from fastrl.data.cohort import make_cohort, replayed_figures

    spec = load_spec(spec_file("triangulation"))
    env = fastrl.make(spec)
    trajs = list(make_cohort(spec, levels=3, per_level=2, seed=0, env=env.unwrapped))
    assert all(t.instruments is not None and t.instruments.shape[1] == 4 for t in trajs)
    figures = [replayed_figures(env, t) for t in trajs]
    by_level = {lv: np.mean([f["return"] for f, t in zip(figures, trajs) if t.meta["skill"] == lv]) for lv in (1, 2, 3)}
    assert by_level[1] < by_level[2] < by_level[3], by_level
    assert all(f["subtasks"] == 5 for f, t in zip(figures, trajs) if t.meta["skill"] == 3)  # level 3: the expert


def test_teleop_tab_switches_to_the_probe_and_the_attempt_keeps_it(tmp_path):
    import time

    from fastrl.data.trajectory import Trajectory
    from fastrl.teleop.session import Session

    s = Session(load_spec(spec_file("triangulation")), "two", tmp_path / "a.npz")
    s.start()
    t = time.monotonic()
    s.on_key(267)  # PageDown: the scope retracts
    s.tick(t)
    s.on_key(258)  # Tab: the probe
    s.on_key(266)  # PageUp: the probe goes in
    for i in range(1, 6):
        s.tick(t + 0.05 * i)
    assert s.writer.actions[:2] == [6, 11 + 4]  # scope retract, then the probe's insert
    s.on_key(256)
    s.tick()
    assert s.finish()
    traj = Trajectory.load(tmp_path / "a.npz")
    assert traj.instruments.shape == (len(traj.time), 4) and traj.instruments[-1, 2] > traj.instruments[0, 2]


@pytest.mark.parametrize("mode", ["discrete", "rates"])
def test_actions_are_recovered_for_scope_and_instrument(mode):
    from fastrl.data.inverse import ActionRecovery, agreement
    from fastrl.data.replay import rollout_trajectory
    from fastrl.data.trajectory import Trajectory

    env = fastrl.make(spec_file("triangulation"), actions={"mode": mode})
    expert = ScriptedExpert(env)
    traj, _ = rollout_trajectory(env, expert.act, 1, {"source": "expert"}, expert.reset)
    traj = Trajectory(traj.time[:120], traj.portal[:120], traj.meta, traj.actions[:119], traj.instruments[:120])
    bare = Trajectory(traj.time, traj.portal, traj.meta, instruments=traj.instruments)
    got = ActionRecovery(fastrl.make(spec_file("triangulation"), actions={"mode": mode})).recover(bare)
    a = agreement(traj.actions, got.actions, mode)
    tool_moves = np.ptp(traj.instruments, axis=0).max() > 0.01
    if mode == "discrete":
        assert tool_moves and a["exact_match"] > 0.95, a  # the probe's actions too, not only the scope's
    else:
        assert tool_moves and a["mean_abs_error"] < 0.05, a
