"""The lean renderer (fastrl.env.lean_scene): the frames of the model as built, per kind, with randomised looks."""

import mujoco
import numpy as np
import pytest

from fastrl.env.fast_env import FastEnv
from fastrl.env.images import EndoscopeFrames
from fastrl.env.lean_scene import LeanScene
from fastrl.spec import load_spec

from ..conftest import spec_file

LOOKS = ["observation.image.looks.colour=0.3", "observation.image.looks.light=0.5"]


def both(kind: str, looks: bool, seed: int = 3, steps: int = 30) -> tuple[np.ndarray, np.ndarray]:
    """Frames of the same states by the model as built (the reference) and by the lean model (the env's own)."""
    sets = ["observation.image.size=32", f"observation.image.kind={kind}", *(LOOKS if looks else [])]
    env = FastEnv(load_spec(spec_file("tracelines"), sets))
    built = EndoscopeFrames(task=env.task, model=env.model, image=env.frames.image, lean=False)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    ref, lean = [], []
    for a in rng.integers(0, 11, steps):
        env.step(int(a))
        ref.append(built.frame(env.data, env.family.done_count))
        lean.append(env.frames.frame(env.data, env.family.done_count))
    built.close()
    env.close()
    return np.stack(ref).astype(int), np.stack(lean).astype(int)


@pytest.mark.parametrize("looks", [False, True])
@pytest.mark.parametrize("kind", ["rgb", "depth", "segmentation"])
def test_lean_frames_match_the_model_as_built(kind, looks):
    ref, lean = both(kind, looks)
    assert ref.std() > 0
    diff = np.abs(ref - lean).max(axis=-1)
    # rgb: the capsules' tubes are lit at their ends only (0.25% of the pixels differ, 0.002% by > 8 levels);
    # depth and segmentation: the same surfaces, a pixel apart where two surfaces tie
    assert (diff > (1 if kind == "rgb" else 2)).mean() <= 0.001, (diff > 0).mean()
    assert (diff > 8).mean() <= (0.0005 if kind == "rgb" else 0.001)
    assert (diff > 0).mean() <= (0.01 if kind == "rgb" else 0.001)


def test_lean_frames_repeat_and_follow_the_looks():
    a, b = both("rgb", True, seed=5), both("rgb", True, seed=5)
    np.testing.assert_array_equal(a[1], b[1])  # deterministic
    assert not np.array_equal(a[1], both("rgb", True, seed=6)[1])


def test_fixed_geoms_become_meshes_and_keep_their_ids():
    env = FastEnv(load_spec(spec_file("tracelines"), ["observation.image.size=32"]))
    lean = LeanScene(task=env.task, model=env.model)
    m, lm = env.model, lean.model
    assert lm.ngeom == m.ngeom and lm.nmesh > 100  # the shell's tiles, the plate, the line's capsules...
    mesh = lm.geom_type == mujoco.mjtGeom.mjGEOM_MESH
    assert not mesh[lean.moving].any() and mesh.sum() == m.ngeom - len(lean.moving)
    np.testing.assert_array_equal(lm.geom_type[lean.moving], m.geom_type[lean.moving])
    assert not mesh[env.task.avatar_geoms.ravel()].any()  # avatars move and change colour with the cue
    assert (m.geom_bodyid[mesh] == 0).all()


@pytest.mark.parametrize("name", ["imagecentring", "liver_tour", "loose_bodies", "triangulation"])
def test_every_family_keeps_its_frames(name):
    """Other scenes' fixed geoms (the cup's walls turned by euler angles, the liver's...) land where they were."""
    env = FastEnv(load_spec(spec_file(name), ["observation.image.size=32"]))
    built = EndoscopeFrames(task=env.task, model=env.model, image=env.frames.image, lean=False)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    diff = []
    for _ in range(10):
        env.step(int(rng.integers(env.action_space.n)))
        diff.append(np.abs(built.frame(env.data, 0).astype(int) - env.frames.frame(env.data, 0)).max(axis=-1))
    assert env.frames.lean.model.nmesh > 0
    assert (np.stack(diff) > 1).mean() <= 0.001
