"""Randomised looks of a pixel task: colours of plate, shell and line, lighting, camera noise and blur."""

from __future__ import annotations

import mujoco
import numpy as np

from ..spec.images import SEGMENTATION_CLASSES, Looks


class RandomLooks:
    """Draws an episode's looks into the env's own model and corrupts its frames; deterministic per reset seed."""

    def __init__(self, *, model: mujoco.MjModel, classes: np.ndarray, looks: Looks):
        self.model, self.looks = model, looks
        surfaces = [SEGMENTATION_CLASSES.index(n) for n in ("plate", "shell", "line")]
        self.geoms = np.flatnonzero(np.isin(classes, surfaces))
        self.rgba = model.geom_rgba[self.geoms].copy()
        self.head = (model.vis.headlight.ambient.copy(), model.vis.headlight.diffuse.copy())
        self.light = model.light_diffuse.copy()
        self.rng = np.random.default_rng(0)
        self.blur = False

    def reset(self, seed: int | None) -> None:
        """A new episode's colours and lighting (a seed restarts the looks' own random stream)."""
        if seed is not None:
            self.rng = np.random.default_rng([seed, 0x100C5])  # apart from the task's stream: same episodes
        lk, m, rng = self.looks, self.model, self.rng
        shift = rng.uniform(-lk.colour, lk.colour, (len(self.geoms), 3))
        m.geom_rgba[self.geoms, :3] = np.clip(self.rgba[:, :3] + shift, 0.0, 1.0)
        scale = 1.0 + rng.uniform(-lk.light, lk.light)
        m.vis.headlight.ambient[:] = self.head[0] * scale
        m.vis.headlight.diffuse[:] = self.head[1] * scale
        m.light_diffuse[:] = self.light * scale
        self.blur = bool(rng.random() < lk.blur)

    def corrupt(self, frame: np.ndarray) -> np.ndarray:
        """The frame blurred (this episode, if drawn) and with pixel noise, as uint8."""
        lk = self.looks
        if not self.blur and lk.noise == 0:
            return frame
        x = frame.astype(np.float32)
        if self.blur:
            p = np.pad(x, ((1, 1), (1, 1), (0, 0)), mode="edge")
            h, w = x.shape[:2]
            x = sum(p[i : i + h, j : j + w] for i in range(3) for j in range(3)) / 9.0
        if lk.noise:
            x = x + self.rng.normal(0.0, lk.noise, x.shape)
        return np.clip(np.rint(x), 0, 255).astype(np.uint8)
