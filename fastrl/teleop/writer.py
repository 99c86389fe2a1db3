"""Incremental saving of an attempt: the partial trajectory is rewritten atomically as it grows."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from ..data.trajectory import Trajectory


class AttemptWriter:
    """Collects samples and writes them to `path` every `every_s` seconds and on close (atomic replace)."""

    def __init__(self, path: Path, meta: dict, every_s: float = 1.0):
        self.path, self.meta, self.every = Path(path), dict(meta), every_s
        self.time, self.portal, self.actions, self.tools, self.bodies = [], [], [], [], []
        self.last_flush = time.monotonic()

    def add(
        self,
        t: float,
        q: np.ndarray,
        action: int | None,
        tools: np.ndarray | None = None,
        bodies: np.ndarray | None = None,
    ) -> None:
        """One sample (the action that led to it, None for the first; the instruments' and loose bodies', if any)."""
        self.time.append(float(t))
        if bodies is not None:
            self.bodies.append(np.asarray(bodies, float).copy())
        if tools is not None:
            self.tools.append(np.asarray(tools, float).copy())
        self.portal.append(np.asarray(q, float).copy())
        if action is not None:
            self.actions.append(int(action))
        if time.monotonic() - self.last_flush >= self.every:
            self.flush()

    def trajectory(self, **meta) -> Trajectory | None:
        """What has been recorded, or None before two samples."""
        if len(self.time) < 2:
            return None
        n = len(self.time)
        actions = np.array(self.actions[-(n - 1) :], np.int64) if len(self.actions) >= n - 1 else None
        tools = np.array(self.tools[:n]) if len(self.tools) >= n else None
        bodies = np.array(self.bodies[:n]) if len(self.bodies) >= n else None
        return Trajectory(np.array(self.time), np.array(self.portal), {**self.meta, **meta}, actions, tools, bodies)

    def flush(self, **meta) -> Path | None:
        """Write the samples so far (meta updated with `meta`); returns the path once something is saved."""
        self.last_flush = time.monotonic()
        traj = self.trajectory(**meta)
        if traj is None:
            return None
        self.meta.update(meta)
        tmp = self.path.with_name(self.path.stem + ".partial.npz")
        traj.save(tmp)
        os.replace(tmp, self.path)
        return self.path
