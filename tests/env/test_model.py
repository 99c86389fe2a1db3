"""The compiler: dome, scope chain, avatars; MJCF round trip to an equivalent model."""

import mujoco
import numpy as np

from fastrl.model import compile_task
from fastrl.model.compiler import build_task
from fastrl.spec import load_spec

from ..conftest import spec_file


def test_mjcf_round_trip_gives_an_equivalent_model(task_name, tmp_path):
    task = compile_task(load_spec(spec_file(task_name)))
    path = tmp_path / "model.xml"
    path.write_text(task.xml)
    loaded = mujoco.MjModel.from_xml_path(str(path))
    m = task.model
    for field in ("nbody", "njnt", "ngeom", "nu", "neq", "ncam", "nlight"):
        assert getattr(loaded, field) == getattr(m, field), field
    assert loaded.opt.timestep == m.opt.timestep
    np.testing.assert_allclose(loaded.geom_pos, m.geom_pos, atol=1e-6)  # MJCF keeps 6 significant digits
    trajectories = []
    for model in (m, loaded):
        d = mujoco.MjData(model)
        d.qpos[task.qadr] = [0.1, -0.1, 0.05, 0.2, 0.3]
        d.qpos[task.lens_qadr] = -0.3
        out = []
        for k in range(200):
            d.ctrl[:] = [0.1 + 0.3 * np.sin(k / 30), -0.1, 0.05 + 0.04 * np.sin(k / 50), 0.5, -0.5]
            mujoco.mj_step(model, d)
            out.append(d.qpos.copy())
        trajectories.append(np.array(out))
    np.testing.assert_allclose(trajectories[0], trajectories[1], atol=1e-6)


def test_scene_has_portals_plate_shell_and_one_avatar_per_subtask(task_name):
    spec = load_spec(spec_file(task_name))
    task = compile_task(spec)
    m = task.model
    names = [m.geom(i).name for i in range(m.ngeom)]
    assert "plate" in names and any(n.startswith("shell_") for n in names)
    assert all(f"portal_{p.name}" in names for p in spec.scene.portals)
    assert len(task.avatar_geoms) == len(task.targets) > 0
    assert np.allclose(np.linalg.norm(task.portal_point), spec.scene.radius)
    if spec.task.line is not None:
        assert any(n.startswith("line_") for n in names)


def test_only_the_tip_can_touch_the_dome():
    task = compile_task(load_spec(spec_file("imagecentring")))
    m = task.model
    tip = task.tip_geom
    for g in range(m.ngeom):
        if g == tip:
            continue
        touches_tip = (m.geom_contype[g] & m.geom_conaffinity[tip]) or (m.geom_contype[tip] & m.geom_conaffinity[g])
        is_world = m.geom_bodyid[g] == 0 and m.geom(g).name.startswith(("shell_", "plate"))
        assert bool(touches_tip) == bool(is_world), m.geom(g).name


def test_angled_optics_tilt_the_view_and_the_cable_sweeps_it_round_a_cone():
    task = compile_task(load_spec(spec_file("periscoping")))
    m, d = task.model, mujoco.MjData(task.model)
    views = []
    for cable in np.linspace(-np.pi, np.pi, 9)[:-1]:
        d.qpos[task.qadr] = [0, 0, 0.05, 0, cable]
        d.qpos[task.lens_qadr] = -cable
        mujoco.mj_kinematics(m, d)
        mujoco.mj_camlight(m, d)
        axis = d.xmat[m.body("scope_shaft").id].reshape(3, 3)[:, 2]
        fwd = -d.cam_xmat[task.camera].reshape(3, 3)[:, 2]
        views.append(fwd)
        assert abs(np.degrees(np.arccos(np.clip(axis @ fwd, -1, 1))) - 30.0) < 1e-6
    assert np.linalg.norm(views[0] - views[4]) > 0.9  # opposite sides of the cone


def test_a_spec_compiled_again_gets_an_equal_model_of_its_own(task_name):
    spec = load_spec(spec_file(task_name))
    first, again = compile_task(spec), compile_task(spec)
    fresh = build_task(spec)
    assert again.model is not first.model
    for name in ("geom_pos", "geom_rgba", "body_pos", "jnt_range", "actuator_gainprm", "opt.timestep"):
        a, b = (np.asarray(model_field(m, name)) for m in (again.model, fresh.model))
        np.testing.assert_array_equal(a, b, err_msg=name)
    first.model.geom_pos[0] += 1.0  # an env moves its avatars: no other env sees it
    assert not np.array_equal(first.model.geom_pos, again.model.geom_pos)
    assert not np.array_equal(first.model.geom_pos, compile_task(spec).model.geom_pos)


def model_field(model, dotted: str):
    """A model field by its dotted name."""
    value = model
    for part in dotted.split("."):
        value = getattr(value, part)
    return value
