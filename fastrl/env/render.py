"""Cheap offscreen views of a compiled task: the endoscope image and an outside view."""

from __future__ import annotations

import mujoco
import numpy as np

from ..model.compiler import CompiledTask

_ENDO = mujoco.MjvOption()
_OUTSIDE = mujoco.MjvOption()
_OUTSIDE.geomgroup[2] = 0  # hide the shell so the inside of the dome shows


def outside_camera(task: CompiledTask) -> mujoco.MjvCamera:
    """A free camera looking down into the dome from the side of the portal."""
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = [0.0, 0.0, 0.03]
    cam.distance = 0.42
    p = task.portal_point
    cam.azimuth = float(np.degrees(np.arctan2(p[1], p[0]))) - 120.0
    cam.elevation = -35.0
    return cam


def render_views(renderer: mujoco.Renderer, model, data, task: CompiledTask, outside: bool) -> dict:
    """Render the endoscope view and optionally the outside view into fresh arrays."""
    renderer.update_scene(data, camera=task.camera, scene_option=_ENDO)
    views = {"endoscope": renderer.render().copy()}
    if outside:
        renderer.update_scene(data, camera=outside_camera(task), scene_option=_OUTSIDE)
        views["outside"] = renderer.render().copy()
    return views
