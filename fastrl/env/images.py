"""The policy's endoscope frames: a lean offscreen renderer, rgb, depth or segmentation as uint8, stacked."""

from __future__ import annotations

import math
import os

import mujoco
import numpy as np

from ..model.compiler import CompiledTask
from ..spec.images import DEPTH_MM_PER_LEVEL, SEGMENTATION_CLASSES, SEGMENTATION_STEP, Image
from .lean_scene import LeanScene
from .looks import RandomLooks
from .render import gl_render, new_renderer

_OPTION = mujoco.MjvOption()
_OPTION.geomgroup[3] = 0  # the scope's internal masses around the camera
_GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)  # an int: numpy compares an array with the enum one element at a time
_ALL = int(mujoco.mjtCatBit.mjCAT_ALL)


def segmentation_classes(model: mujoco.MjModel, task: CompiledTask) -> np.ndarray:
    """Each geom's segmentation class (index into SEGMENTATION_CLASSES); avatars are classed per frame."""
    classes = np.full(model.ngeom, SEGMENTATION_CLASSES.index("instrument"), np.uint8)
    for g in range(model.ngeom):
        name = model.geom(g).name
        if name == "plate":
            classes[g] = SEGMENTATION_CLASSES.index("plate")
        elif model.geom_bodyid[g] == 0 and not name.startswith(("line", "avatar")):
            classes[g] = SEGMENTATION_CLASSES.index("shell")  # shell tiles, crown, portal rims, abdomen
        elif name.startswith("line"):
            classes[g] = SEGMENTATION_CLASSES.index("line")
    classes[task.avatar_geoms.ravel()] = SEGMENTATION_CLASSES.index("other avatar")
    return classes


def visible_geoms(model: mujoco.MjModel, data: mujoco.MjData, camera: int, cos_half: float) -> np.ndarray:
    """Geoms whose bounding sphere may meet the camera's view cone (a cone round the square frame's corners)."""
    rel = data.geom_xpos - data.cam_xpos[camera]
    fwd = -data.cam_xmat[camera].reshape(3, 3)[:, 2]
    along = rel @ fwd
    dist = np.sqrt((rel * rel).sum(axis=1))
    sin_half = math.sqrt(1.0 - cos_half * cos_half)
    # angle to the axis minus the cone's half angle, as a distance: inside when below the bounding radius
    lateral = np.sqrt(np.maximum(dist * dist - along * along, 0.0))
    outside = lateral * cos_half - along * sin_half
    return (outside < model.geom_rbound) | (dist < model.geom_rbound)


_SHARED: dict[tuple, mujoco.Renderer] = {}  # per process: the lean envs of one task, size and kind share a context


def renderer(model: mujoco.MjModel, image: Image, key: tuple | None) -> mujoco.Renderer:
    """An offscreen renderer for the image's size and kind; one per key in a process (None: a new one)."""
    if key in _SHARED:
        return _SHARED[key]
    r = new_renderer(model, image.size, image.size)
    if image.kind == "depth":
        r.enable_depth_rendering()
    elif image.kind == "segmentation":
        r.enable_segmentation_rendering()
    if key is not None:
        _SHARED[key] = r  # the lean models of a task are copies: the same meshes in every env's GL context
    return r


class EndoscopeFrames:
    """Renders the endoscope as the policy sees it and keeps the last `stack` frames (H, W, C * stack) uint8."""

    def __init__(self, *, task: CompiledTask, model: mujoco.MjModel, image: Image, lean: bool = True):
        self.task, self.model, self.image = task, model, image
        self.camera = task.camera
        half = math.radians(0.5 * model.cam_fovy[self.camera])
        self.cos_half = math.cos(math.atan(math.tan(half) * math.sqrt(2.0)))  # the square frame's corners
        needs = image.kind == "segmentation" or image.looks is not None
        self.classes = segmentation_classes(model, task) if needs else None
        self.looks = None if image.looks is None else RandomLooks(model=model, classes=self.classes, looks=image.looks)
        self.shape = (image.size, image.size, image.channels * image.stack)
        self.frames = np.zeros(self.shape, np.uint8)
        self.renderer: mujoco.Renderer | None = None  # made on first use: in the process that steps the env
        self.view = mujoco.MjvCamera()
        self.view.type, self.view.fixedcamid = mujoco.mjtCamera.mjCAMERA_FIXED, self.camera
        self.lean: LeanScene | bool = lean  # the fixed geoms drawn as meshes (fastrl.env.lean_scene); False: as built

    def _render(self, data: mujoco.MjData) -> np.ndarray:
        """The raw frame: rgb uint8, depth float metres or segmentation ids, geoms out of view left out."""
        if self.renderer is None:
            self.lean = self.lean and LeanScene(task=self.task, model=self.model)
            key = (os.getpid(), self.task.spec.model_dump_json(), self.image.size, self.image.kind)  # not a parent's
            key = key if self.lean else None
            self.renderer = renderer(self.lean.model if self.lean else self.model, self.image, key)
        m, data = (self.lean.model, self.lean.sync(data)) if self.lean else (self.model, data)
        hidden = ~visible_geoms(m, data, self.camera, self.cos_half)
        alpha = m.geom_rgba[hidden, 3].copy()
        m.geom_rgba[hidden, 3] = 0.0  # a geom of alpha 0 is not drawn: out of view, it costs nothing
        try:
            mujoco.mjv_updateScene(m, data, _OPTION, None, self.view, _ALL, self.renderer.scene)
        finally:
            m.geom_rgba[hidden, 3] = alpha
        return gl_render(self.renderer)

    def frame(self, data: mujoco.MjData, subtask: int) -> np.ndarray:
        """One frame (H, W, C) uint8 of the current state; `subtask` is the active avatar (segmentation)."""
        raw = self._render(data)
        kind = self.image.kind
        if kind == "rgb":
            return raw
        if kind == "depth":
            levels = np.rint(raw * (1000.0 / DEPTH_MM_PER_LEVEL))
            return np.clip(levels, 0, 255).astype(np.uint8)[:, :, None]
        ids, types = raw[:, :, 0], raw[:, :, 1]
        classes = self.classes.copy()
        if subtask < len(self.task.avatar_geoms):
            disk, mark = self.task.avatar_geoms[subtask]
            classes[disk] = SEGMENTATION_CLASSES.index("active avatar")
            classes[mark] = SEGMENTATION_CLASSES.index("active avatar's up mark")
        is_geom = (types == _GEOM) & (ids >= 0)
        labels = np.where(is_geom, classes[np.where(is_geom, ids, 0)], 0)
        return (labels * SEGMENTATION_STEP).astype(np.uint8)[:, :, None]

    def reset(self, seed: int | None) -> None:
        """A new episode: draw its looks, if the spec randomises them."""
        if self.looks is not None:
            self.looks.reset(seed)

    def observe(self, data: mujoco.MjData, subtask: int, first: bool) -> np.ndarray:
        """Render, push the frame onto the stack (filling it at an episode's start) and return a copy."""
        f = self.frame(data, subtask)
        if self.looks is not None:
            f = self.looks.corrupt(f)
        c = f.shape[2]
        if first:
            self.frames[:] = np.tile(f, (1, 1, self.image.stack))
        else:
            self.frames[:, :, :-c] = self.frames[:, :, c:]
            self.frames[:, :, -c:] = f
        return self.frames.copy()

    def close(self) -> None:
        """Free the renderer (a shared one stays for the process's other envs)."""
        if self.renderer is not None and not self.lean:
            self.renderer.close()
        self.renderer = None
