"""Endoscope-image observations: spaces, kinds, stacking, determinism, the env checkers, faithful culling."""

import math
import warnings

import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from fastrl.env.fast_env import FastEnv
from fastrl.env.images import _OPTION, EndoscopeFrames
from fastrl.spec import SpecError, load_spec, spec_hash, task_hash
from fastrl.spec.images import SEGMENTATION_CLASSES, SEGMENTATION_STEP

from ..conftest import spec_file


def pixel_env(name="tracelines", **image) -> FastEnv:
    """A bundled task with an image observation."""
    sets = [f"observation.image.{k}={str(v).lower() if isinstance(v, bool) else v}" for k, v in image.items()]
    return FastEnv(load_spec(spec_file(name), sets or ["observation.image.size=32"]))


@pytest.mark.parametrize("kind, channels", [("rgb", 3), ("depth", 1), ("segmentation", 1)])
def test_frames_have_the_declared_shape_and_dtype(kind, channels):
    env = pixel_env(kind=kind, size=40, stack=3)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.shape == (40, 40, 3 * channels) and env.observation_space.dtype == np.uint8
    assert obs.shape == (40, 40, 3 * channels) and obs.dtype == np.uint8 and env.observation_space.contains(obs)
    assert obs.std() > 0  # the frame shows something
    np.testing.assert_array_equal(obs[:, :, :channels], obs[:, :, -channels:])  # the stack starts full of frame 0
    for _ in range(5):
        obs, *_ = env.step(1)  # pitch: the view moves
    assert not np.array_equal(obs[:, :, :channels], obs[:, :, -channels:])
    env.close()


def test_state_rides_beside_the_image_as_a_dict():
    kinematic = FastEnv(load_spec(spec_file("tracelines")))
    env = pixel_env(state=True, size=32)
    obs, _ = env.reset(seed=4)
    assert set(obs) == {"image", "state"} and env.observation_space.contains(obs)
    np.testing.assert_array_equal(obs["state"], kinematic.reset(seed=4)[0])
    for a in (3, 3, 5):
        obs, *_ = env.step(a)
        np.testing.assert_array_equal(obs["state"], kinematic.step(a)[0])
    np.testing.assert_array_equal(env.observation()["image"], obs["image"])


def test_same_seed_gives_the_same_frames():
    def frames(seed):
        env = pixel_env(size=32, stack=2)
        out = [env.reset(seed=seed)[0]]
        rng = np.random.default_rng(7)
        out += [env.step(int(a))[0] for a in rng.integers(0, 11, 30)]
        env.close()
        return np.stack(out)

    a = frames(5)
    np.testing.assert_array_equal(a, frames(5))
    assert not np.array_equal(a, frames(6))  # the start pose's noise differs


@pytest.mark.parametrize("state", [False, True])
def test_gymnasium_and_sb3_checkers_pass(state):
    env = pixel_env(size=48, stack=2, state=state)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the state's infinite bounds, as for the kinematic specs
        check_env(env, skip_render_check=True)
        sb3_check_env(env, warn=True)


def test_culled_frames_match_the_full_scene():
    """The cull alone (the model as built, not the lean meshes: tests/env/test_lean_scene.py) changes no pixel."""
    env = pixel_env(size=48)
    env.reset(seed=2)
    culled = EndoscopeFrames(task=env.task, model=env.model, image=env.frames.image, lean=False)
    full = mujoco.Renderer(env.model, 48, 48)
    rng = np.random.default_rng(0)
    for a in rng.integers(0, 11, 40):
        env.step(int(a))
        full.update_scene(env.data, camera=env.task.camera, scene_option=_OPTION)
        np.testing.assert_array_equal(culled.frame(env.data, 0), full.render())
    full.close()
    culled.close()


def test_depth_is_millimetres_along_the_optical_axis():
    env = pixel_env(kind="depth", size=32)
    env.reset(seed=0)
    pos, fwd = np.array(env.state.cam_pos), np.array(env.state.cam_fwd)
    assert fwd[2] < -0.3  # the start pose looks down at the plate
    to_plate = -pos[2] / fwd[2] * 1000.0  # the plate's top is z = 0
    centre = env.observation()[15:17, 15:17, 0].astype(float).mean()
    assert abs(centre - to_plate) <= 2.0, (centre, to_plate)


def test_segmentation_labels_the_line_and_the_active_avatar():
    env = pixel_env("tracelines", kind="segmentation", size=64)
    obs, _ = env.reset(seed=0)
    levels = set(np.unique(obs).tolist())
    assert levels <= {k * SEGMENTATION_STEP for k in range(len(SEGMENTATION_CLASSES))}
    for name in ("plate", "line", "active avatar"):
        assert SEGMENTATION_CLASSES.index(name) * SEGMENTATION_STEP in levels, name


def test_images_change_only_spec_hash():
    spec = load_spec(spec_file("tracelines"))
    pixels = load_spec(spec_file("tracelines"), ["observation.image.size=48"])
    assert task_hash(pixels) == task_hash(spec) and spec_hash(pixels) != spec_hash(spec)
    assert FastEnv(spec).observation_space == FastEnv(load_spec(spec_file("tracelines"))).observation_space


@pytest.mark.parametrize(
    "sets, field",
    [
        (["observation.image.size=16"], "observation.image.size"),
        (["observation.image.kind=infrared"], "observation.image.kind"),
        (["observation.image.stack=0"], "observation.image.stack"),
        (["observation.image.size=32", "irl.algorithm=gail"], "irl.algorithm"),
        (["observation.image.size=32", "irl.algorithm=airl"], "irl.algorithm"),
    ],
)
def test_bad_image_settings_name_their_field(sets, field):
    with pytest.raises(SpecError) as e:
        load_spec(spec_file("tracelines"), sets)
    assert field in str(e.value)


def test_frames_cost_less_than_the_whole_scene():
    """The cull keeps only geoms near the view cone: far fewer than the scene holds (the shell's tiles)."""
    from fastrl.env.images import visible_geoms

    env = pixel_env(size=32)
    env.reset(seed=0)
    frames = env.frames
    seen = visible_geoms(env.model, env.data, env.task.camera, frames.cos_half)
    assert 0 < seen.sum() < 0.6 * env.model.ngeom
    assert math.isclose(frames.cos_half, math.cos(math.atan(math.tan(math.radians(40)) * math.sqrt(2))))


LOOKS = [
    "observation.image.size=32",
    "observation.image.looks.colour=0.3",
    "observation.image.looks.light=0.5",
    "observation.image.looks.noise=4",
    "observation.image.looks.blur=0.5",
]


def test_random_looks_vary_by_episode_and_repeat_by_seed():
    env = FastEnv(load_spec(spec_file("tracelines"), LOOKS))
    plain = FastEnv(load_spec(spec_file("tracelines"), ["observation.image.size=32"]))
    a, b, c = env.reset(seed=1)[0], env.reset(seed=2)[0], env.reset(seed=1)[0]
    np.testing.assert_array_equal(a, c)  # the same seed: the same looks and noise
    plate = env.model.geom("plate").id
    colours = set()
    for seed in range(4):
        env.reset(seed=seed)
        colours.add(tuple(env.model.geom_rgba[plate].round(6)))
    assert len(colours) == 4  # every episode its own plate colour
    # the task is the same: its state, and so the kinematic rollout, does not depend on the looks
    for seed in (1, 2):
        env.reset(seed=seed)
        plain.reset(seed=seed)
        for action in (1, 4, 7):
            env.step(action)
            plain.step(action)
        assert env.state.portal == plain.state.portal and env.state.distance == plain.state.distance
    assert not np.array_equal(a, b)


def test_without_looks_the_compiled_colours_stay():
    env = pixel_env(size=32)
    before = env.model.geom_rgba.copy()
    for seed in range(3):
        env.reset(seed=seed)
        env.step(2)
    np.testing.assert_array_equal(
        env.model.geom_rgba[: env.task.avatar_geoms.min()], before[: env.task.avatar_geoms.min()]
    )
