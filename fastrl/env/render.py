"""Cheap offscreen views of a compiled task: the endoscope image and an outside view."""

from __future__ import annotations

import mujoco
import numpy as np

from ..forked import deferred
from ..model.compiler import CompiledTask

_MADE_CONTEXT = False  # whether this process (or the one it was forked from) made a GL context
_ENDO = mujoco.MjvOption()
_OUTSIDE = mujoco.MjvOption()
_OUTSIDE.geomgroup[2] = 0  # hide the shell so the inside of the dome shows


def new_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """An offscreen renderer (its own GL context); the process remembers it made one (rendered_here)."""
    global _MADE_CONTEXT
    _MADE_CONTEXT = True
    with deferred():  # see gl_render
        return mujoco.Renderer(model, height, width)


def gl_render(renderer: mujoco.Renderer) -> np.ndarray:
    """renderer.render() with Ctrl-C and SIGTERM deferred: a stop inside EGL's ctypes calls would come out as a
    ctypes.ArgumentError (a traceback), not as a stop; deferred, it comes once the frame is done."""
    with deferred():
        return renderer.render()


def rendered_here() -> bool:
    """Whether this process, or the one it was forked from, made a GL context: a child forked from it would
    deadlock in Mesa's EGL as soon as it rendered itself."""
    return _MADE_CONTEXT


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
    views = {"endoscope": gl_render(renderer).copy()}
    if outside:
        renderer.update_scene(data, camera=outside_camera(task), scene_option=_OUTSIDE)
        views["outside"] = gl_render(renderer).copy()
    return views
