"""The FAST environments: API checks, determinism, fulcrum, cues, reward, replay, rendering."""

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import fastrl
from fastrl.agents.expert import ScriptedExpert
from fastrl.model.kinematics import Kinematics, solve_view

from ..conftest import spec_file

IDS = {
    "imagecentring": "fastrl/ImageCentring-v0",
    "periscoping": "fastrl/Periscoping-v0",
    "tracelines": "fastrl/TraceLines-v0",
}


@pytest.mark.parametrize("mode", ["discrete", "continuous", "rates"])
def test_gymnasium_and_sb3_checkers_pass(task_name, mode):
    env = gymnasium.make(IDS[task_name], actions={"mode": mode})
    gym_check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=False)
    assert env.action_space.shape == {"discrete": (), "continuous": (7,), "rates": (5,)}[mode]
    if mode == "discrete":
        assert env.action_space.n == 11


def rollout(env, actions, seed):
    """Observations of a fixed action sequence."""
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, *_ = env.step(a)
        out.append(obs)
    return np.array(out)


def test_same_seed_and_actions_give_identical_observations(task_name):
    actions = np.random.default_rng(1).integers(0, 11, 150)
    a = rollout(fastrl.make(spec_file(task_name)), actions, seed=7)
    b = rollout(fastrl.make(spec_file(task_name)), actions, seed=7)
    c = rollout(fastrl.make(spec_file(task_name)), actions, seed=8)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("mode", ["discrete", "continuous", "rates"])
def test_the_shaft_always_passes_through_the_portal_point(mode):
    env = fastrl.make(spec_file("imagecentring"), actions={"mode": mode})
    u = env.unwrapped
    shaft = u.model.body("scope_shaft").id
    point = u.task.portal_point
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    worst, contacts = 0.0, 0
    for _ in range(600):
        a = rng.integers(0, 11) if mode == "discrete" else rng.uniform(-1, 1, env.action_space.shape)
        _, _, term, trunc, info = env.step(a)
        tip, axis = u.data.xpos[shaft], u.data.xmat[shaft].reshape(3, 3)[:, 2]
        worst = max(worst, np.linalg.norm(np.cross(point - tip, axis)))
        assert np.allclose(u.data.cam_xpos[u.task.camera], tip, atol=1e-9)
        contacts += info["contacts"] > 0
        if term or trunc:
            env.reset()
    assert worst < 1e-6


def test_the_tip_is_stopped_by_the_plate():
    env = fastrl.make(spec_file("imagecentring"), overrides=["episode.resets={}"])
    u = env.unwrapped
    env.reset(seed=0)
    env.unwrapped.set_portal_coordinates([0.45, 0.0, 0.06, 0.0, 0.0])  # shaft steeply down toward the plate
    for _ in range(60):
        _, _, _, _, info = env.step(5)  # keep inserting
    assert info["contacts"] > 0
    assert u.data.cam_xpos[u.task.camera][2] > -0.001  # did not pass through


def test_the_contact_observation_is_the_contact_feature_and_replays_identically():
    env = fastrl.make(spec_file("imagecentring"), observation={"extra": ["contact"]})
    obs, _ = env.reset(seed=3)
    coords, seen, felt = [env.unwrapped.portal_coordinates()], [obs], []
    for _ in range(200):  # keep inserting: the tip reaches a surface and presses on it
        obs, _, _, _, info = env.step(5)
        coords.append(env.unwrapped.portal_coordinates())
        seen.append(obs)
        felt.append(info["features"]["contact"])
    assert [o[-1] for o in seen[1:]] == felt
    assert 0 < sum(felt) < len(felt)  # free at first, then touching
    replay = fastrl.make(spec_file("imagecentring"), observation={"extra": ["contact"]}).unwrapped
    replay.reset(seed=3, options={"portal": coords[0]})
    replayed = [replay.replay_step(q)[0] for q in coords[1:]]
    np.testing.assert_allclose(replayed, seen[1:], atol=1e-9)


def test_the_elapsed_observation_counts_to_the_time_limit_and_restarts_at_reset():
    env = fastrl.make(spec_file("tracelines"), observation={"extra": ["elapsed"]}, episode={"time_limit": 2})
    obs, _ = env.reset(seed=0)
    seen, done = [obs[-1]], False
    while not done:
        obs, _, term, trunc, _ = env.step(0)  # no-op: the scope holds still until the time limit
        seen.append(obs[-1])
        done = term or trunc
    assert trunc and not term
    np.testing.assert_allclose(seen, np.arange(len(seen)) / (len(seen) - 1), atol=1e-6)  # 0 at reset, 1 at the limit
    assert env.reset(seed=1)[0][-1] == 0.0


def goal_pose(env, k=0):
    """Portal coordinates that satisfy subtask k's cues."""
    u = env.unwrapped
    q, _ = solve_view(Kinematics(u.task), k, u.portal_coordinates())
    return q


def test_cues_hold_at_the_solved_view_and_the_dwell_completes_on_time():
    env = fastrl.make(spec_file("imagecentring"))
    env.reset(seed=0)
    q = goal_pose(env)
    u = env.unwrapped
    u.set_portal_coordinates(q)
    steps_needed = int(np.ceil(u.task_spec.task.cue.dwell * u.task_spec.episode.control_hz - 1e-9))
    for i in range(1, steps_needed):
        _, _, _, _, info = u.replay_step(q)
        assert all(info["cue"][k] for k in ("centring", "horizon", "distance", "green"))
        assert info["subtask"] == 0 and info["features"]["completed"] == 0.0
        assert info["cue"]["dwell"] == pytest.approx(i / steps_needed)
    _, _, _, _, info = u.replay_step(q)
    assert info["subtask"] == 1 and info["features"]["completed"] == 1.0
    assert not info["cue"]["green"]  # the cue now describes the next avatar


def test_leaving_tolerance_resets_the_dwell():
    env = fastrl.make(spec_file("imagecentring"))
    env.reset(seed=0)
    u = env.unwrapped
    q = goal_pose(env)
    u.replay_step(q)
    _, _, _, _, info = u.replay_step(q)
    assert info["cue"]["dwell"] > 0
    away = q + np.array([0.4, 0, 0, 0, 0])
    _, _, _, _, info = u.replay_step(away)
    assert not info["cue"]["green"] and info["cue"]["dwell"] == 0.0


def test_reward_is_the_weighted_sum_of_features_and_weights_change_live():
    env = fastrl.make(spec_file("tracelines"))
    env.reset(seed=0)
    u = env.unwrapped
    _, r, _, _, info = env.step(1)
    w = u.reward_weights()
    assert r == pytest.approx(sum(w[k] * v for k, v in info["features"].items()))
    u.set_reward_weights({"time": -5.0})
    _, r2, _, _, info2 = env.step(0)
    assert r2 == pytest.approx(sum(u.reward_weights()[k] * v for k, v in info2["features"].items()))
    assert u.reward_weights()["time"] == -5.0
    with pytest.raises(ValueError, match="unknown reward features"):
        u.set_reward_weights({"nope": 1.0})


def test_info_has_the_documented_keys(task_name):
    env = fastrl.make(spec_file(task_name))
    _, info = env.reset(seed=0)
    _, _, _, _, info = env.step(0)
    assert {"features", "subtask", "subtasks_total", "cue", "success"} <= set(info)
    assert set(info["features"]) == set(env.unwrapped.task_spec.reward.features)
    assert {"centring", "horizon", "distance", "green", "dwell"} <= set(info["cue"])


def test_bad_actions_raise_and_out_of_range_continuous_actions_are_clipped():
    env = fastrl.make(spec_file("imagecentring"))
    env.reset(seed=0)
    for bad in (float("nan"), 11, -1, 2.5):
        with pytest.raises(ValueError):
            env.step(bad)
    envs = [fastrl.make(spec_file("imagecentring"), actions={"mode": "continuous"}) for _ in range(2)]
    for e in envs:
        e.reset(seed=3)
    with pytest.raises(ValueError, match="non-finite"):
        envs[0].step(np.array([np.inf, 0, 0, 0, 0, 0, 0]))
    a, b = envs[0].step(np.full(7, 5.0))[0], envs[1].step(np.ones(7))[0]
    assert np.array_equal(a, b)


def test_rate_actions_move_each_coordinate_at_its_maximum_rate():
    env = fastrl.make(spec_file("tracelines"), actions={"mode": "rates"}, overrides=["episode.resets={}"])
    u = env.unwrapped
    c = u.task_spec.actions
    rates = np.radians([c.max_pivot_rate_deg, c.max_pivot_rate_deg, 0, c.max_roll_rate_deg, 0])
    rates[2], rates[4] = c.max_insertion_rate, c.max_cable_rate
    for k in range(5):
        env.reset(seed=0)
        q0 = u.portal_coordinates()
        a = np.zeros(5, np.float32)
        a[k] = -0.5 if k == 2 else 0.5  # retract rather than push into the plate
        for _ in range(10):
            env.step(a)
        moved = u.portal_coordinates() - q0
        expected = a[k] * rates[k] * 10 * u.dt
        assert moved[k] == pytest.approx(expected, rel=0.15), (k, moved)
        assert np.all(np.abs(np.delete(moved, k)) < 0.1 * abs(expected) + 1e-4), (k, moved)
    with pytest.raises(ValueError, match="5 values"):
        env.step(np.zeros(7))


def test_truncates_at_the_time_limit():
    env = fastrl.make(spec_file("periscoping"), episode={"time_limit": 1.0})
    env.reset(seed=0)
    for _ in range(20):
        _, _, term, trunc, _ = env.step(0)
    assert trunc and not term


def test_replaying_portal_coordinates_recomputes_identical_observations_and_features(task_name):
    env = fastrl.make(spec_file(task_name))
    expert = ScriptedExpert(env)
    obs, _ = env.reset(seed=4)
    coords, observations, feats = [env.unwrapped.portal_coordinates()], [obs], []
    for _ in range(120):
        obs, _, term, trunc, info = env.step(expert.act(obs))
        coords.append(env.unwrapped.portal_coordinates())
        observations.append(obs)
        feats.append(info["features"])
        if term or trunc:
            break
    replay = fastrl.make(spec_file(task_name)).unwrapped
    obs, _ = replay.reset(seed=4, options={"portal": coords[0]})
    assert np.array_equal(obs, observations[0])
    for q, want_obs, want_feats in zip(coords[1:], observations[1:], feats):
        obs, _, _, _, info = replay.replay_step(q)
        np.testing.assert_allclose(obs, want_obs, atol=1e-9)
        assert info["features"] == pytest.approx(want_feats, abs=1e-9)


def test_render_returns_an_endoscope_image_and_an_outside_view():
    env = fastrl.make(spec_file("imagecentring"), render_mode="rgb_array", width=64, height=48)
    env.reset(seed=0)
    img = env.render()
    assert img.shape == (48, 64, 3) and img.dtype == np.uint8 and img.std() > 1.0
    views = env.unwrapped.render_views()
    assert views["outside"].shape == (48, 64, 3) and not np.array_equal(views["outside"], views["endoscope"])
    env.close()


def test_portal_coordinates_round_trip_and_are_clipped_to_their_ranges():
    env = fastrl.make(spec_file("imagecentring"))
    env.reset(seed=0)
    u = env.unwrapped
    q = np.array([0.2, -0.1, 0.07, 0.5, -1.0])
    u.set_portal_coordinates(q)
    assert np.allclose(u.portal_coordinates(), q)
    u.set_portal_coordinates([5.0, 0, 1.0, 0, 0])
    assert np.allclose(u.portal_coordinates()[[0, 2]], u.task.ranges[[0, 2], 1])
    with pytest.raises(ValueError):
        u.set_portal_coordinates([0, 0, np.nan, 0, 0])


def test_rays_see_the_avatar_at_the_solved_view_and_not_when_looking_away():
    env = fastrl.make(spec_file("periscoping"))
    env.reset(seed=0)
    u = env.unwrapped
    q = goal_pose(env)
    _, _, _, _, info = u.replay_step(q)
    assert info["features"]["rays"] == 1.0
    _, _, _, _, info = u.replay_step(q + np.array([0, 0, 0, 0, np.pi]))  # light cable half a turn away
    assert info["features"]["rays"] == 0.0


@pytest.mark.parametrize(
    ("algo", "setting", "expected"),
    [("PPO", None, True), ("SAC", None, False), ("SAC", True, True), ("PPO", False, False)],
)
def test_reward_normalisation_defaults_on_for_ppo_and_off_for_sac(algo, setting, expected):
    from fastrl.agents.sb3 import make_vec_env
    from fastrl.spec import load_spec

    sets = [f"train.algo={algo}", "actions.mode=rates"]
    if setting is not None:
        sets.append(f"train.normalize.reward={str(setting).lower()}")
    venv = make_vec_env(load_spec(spec_file("tracelines"), sets), 1, 0)
    assert venv.norm_reward is expected


def test_stepping_after_a_replayed_pose_matches_stepping_after_placing_it():
    no_clock = {"extra": ["contact"]}  # replay_step advances the clock, placing does not: compare the pose alone
    a, b = (fastrl.make(spec_file("tracelines"), observation=no_clock) for _ in range(2))
    a.reset(seed=4)
    b.reset(seed=4)
    q = a.unwrapped.portal_coordinates() + np.array([0.02, -0.01, 0.003, 0.1, 0.2])
    a.unwrapped.replay_step(q)  # positions only
    b.unwrapped.set_portal_coordinates(q)  # full forward
    for action in (1, 3, 5, 9, 0):
        oa, *_ = a.step(action)
        ob, *_ = b.step(action)
        assert np.allclose(oa, ob, atol=1e-6)


def test_later_subtasks_start_unseeded_episodes_at_a_later_avatar_the_expert_then_finishes():
    """A forward-RL env's episodes after its first start at a random later avatar, the earlier ones done, in the
    state, the observation and the colours; seeded resets (evaluations) and replays (options) start at the first;
    the same seeds draw the same starts, and the scripted expert finishes the task from one."""
    from fastrl.env import FastEnv
    from fastrl.spec import load_spec
    from fastrl.terms.observations import subtask_fraction

    spec = load_spec(spec_file("imagecentring"))
    env, twin = FastEnv(spec, later_subtasks=1.0), FastEnv(spec, later_subtasks=1.0)
    total = env.state.subtasks_total
    env.reset(seed=3)
    twin.reset(seed=3)
    assert env.state.subtasks_done == env.state.subtask == 0
    starts = []
    for _ in range(20):
        obs, _ = env.reset()
        twin.reset()
        s, k = env.state, env.state.subtasks_done
        starts.append(k)
        assert twin.state.subtasks_done == k and s.subtask == k and s.target_pos == tuple(env.family.t_pos[k])
        assert subtask_fraction(s) == (pytest.approx(k / total),) and s.dwell == 0.0 and s.prev_potential == s.potential
    assert set(starts) == set(range(1, total))
    env.reset(seed=4)
    assert env.state.subtasks_done == 0
    env.reset(options={"portal": env.portal_coordinates()})
    assert env.state.subtasks_done == 0
    obs, _ = env.reset()
    first = env.state.subtasks_done
    expert = ScriptedExpert(env)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, _, terminated, truncated, info = env.step(expert.act(obs))
    assert terminated and env.state.subtasks_done == total and first >= 1
    untouched = FastEnv(spec)
    untouched.reset(seed=3)
    untouched.reset()
    assert untouched.state.subtasks_done == 0  # the default: every episode at the first


def test_recorded_starts_continue_a_recording_mid_way_and_the_expert_then_finishes():
    """A generator env's unseeded episodes start at a state of a given recording (its pose, its avatars done, its
    clock), the same seeds draw the same starts, seeded resets (evaluations) start as the spec says, and the scripted
    expert finishes the task from one."""
    from fastrl.data.replay import expert_trajectories
    from fastrl.env import FastEnv
    from fastrl.spec import load_spec

    spec = load_spec(spec_file("tracelines"))
    (demo,) = expert_trajectories(FastEnv(spec), [7])
    recorded = ((7, demo.portal),)
    env, twin = (FastEnv(spec, recorded=recorded, recorded_starts=1.0) for _ in range(2))
    env.reset(seed=3)
    twin.reset(seed=3)
    assert env.steps == 0 and env.state.subtasks_done == 0
    replay = FastEnv(spec)
    starts = []
    for _ in range(8):
        obs, _ = env.reset()
        twin_obs, _ = twin.reset()
        t = env.steps
        starts.append(t)
        np.testing.assert_array_equal(obs, twin_obs)
        np.testing.assert_allclose(env.portal_coordinates(), demo.portal[t], atol=1e-9)
        replay.reset(seed=7, options={"portal": demo.portal[0]})
        for q in demo.portal[1 : t + 1]:
            replay.replay_step(q)
        assert env.state.subtasks_done == replay.state.subtasks_done and env.state.time == pytest.approx(t * env.dt)
    assert len(set(starts)) > 4 and max(starts) < len(demo.portal) - 1
    expert = ScriptedExpert(env)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, _, terminated, truncated, info = env.step(expert.act(obs))
    assert terminated and info["success"] and env.steps > starts[-1]
    env.reset(seed=4)
    assert env.steps == 0 and env.state.subtasks_done == 0


def test_late_starts_run_the_clock_on_unseeded_resets_only():
    """A generator env's episodes after its first start late, on the clock the policy observes; seeded resets
    (evaluations) and replays (options) always start at 0 s, and a late episode ends at the time limit."""
    from fastrl.env import FastEnv
    from fastrl.spec import load_spec
    from fastrl.terms.observations import elapsed

    env = FastEnv(load_spec(spec_file("tracelines")), late_starts=0.75)
    env.reset(seed=3)
    assert env.steps == 0 and elapsed(env.state) == (0.0,)
    starts = []
    for _ in range(30):
        env.reset()
        starts.append(env.steps)
        assert elapsed(env.state)[0] == pytest.approx(env.steps / env.max_steps)
    assert 0 < max(starts) <= 0.75 * env.max_steps and len(set(starts)) > 10
    env.reset(options={"portal": env.portal_coordinates()})
    assert env.steps == 0
    env.reset(seed=4)
    env.reset()
    while env.steps < 5:  # a late start that leaves a few steps: redraw until one does not start at 0
        env.reset()
    left, steps, terminated, truncated = env.max_steps - env.steps, 0, False, False
    while not (terminated or truncated):
        *_, terminated, truncated, _ = env.step(0)
        steps += 1
    assert truncated and steps == left


def test_line_distance_grid_is_computed_once_then_read_from_the_cache(tmp_path, monkeypatch):
    from scipy.spatial import cKDTree

    from fastrl.env.sensing import DistanceGrid
    from fastrl.spec.geometry import sample_polyline

    monkeypatch.setenv("FASTRL_CACHE", str(tmp_path))
    line = np.array([[0.04, -0.04], [0.01, -0.01], [-0.01, 0.03], [-0.05, 0.04]])
    grid = DistanceGrid(line, extent=0.05)
    xs = grid.axis
    gx, gy = np.meshgrid(xs, xs, indexing="ij")
    tree = cKDTree(sample_polyline(line, 0.25 * grid.cell))
    whole = np.minimum(tree.query(np.column_stack([gx.ravel(), gy.ravel()]))[0], grid.cap).reshape(gx.shape)
    assert np.array_equal(grid.values, whole) and np.array_equal(np.array(grid.grid), whole)
    (saved,) = (tmp_path / "line-distance").glob("*.npy")
    saved.write_bytes(b"\x93NUMPY" + b"\x00" * 40)  # corrupt: computed again, the same
    assert np.array_equal(DistanceGrid(line, extent=0.05).values, whole)
    np.save(saved, np.zeros_like(whole))  # what the cache holds is what is read (no second computation)
    assert not DistanceGrid(line, extent=0.05).values.any()
    assert DistanceGrid(line, extent=0.06).values.shape != whole.shape  # another grid: another file
    points = np.random.default_rng(0).uniform(-0.06, 0.06, (3000, 2))
    one_by_one = [grid(x, y) for x, y in points]
    assert np.array_equal(grid.lookup(points[:, 0], points[:, 1]), one_by_one) and max(one_by_one) == grid.cap
