"""The instruments of an episode in Rerun: each shaft and tip per step, each tip's path, and the loose bodies."""

from __future__ import annotations

import numpy as np
import rerun as rr

from ..data.episode import EpisodeRecord
from ..model.compiler import CompiledTask
from ..model.loose import BODY_RGBA
from .shapes import rgba

TOOL = rgba((0.75, 0.72, 0.45))
TOOL_PATH = rgba((0.95, 0.6, 0.2))


def log_instruments(rec: rr.RecordingStream, world: str, ep: EpisodeRecord, index: list, task: CompiledTask) -> None:
    """`{world}/{name}/shaft` and `/tip` on the step timelines, `/path` static; nothing without instruments."""
    if ep.bodies is not None:
        _log_bodies(rec, world, ep, index, task)
    if ep.tools is None:
        return
    n = len(ep.time)
    for i, handle in enumerate(task.instruments):
        name, d = handle.spec.name, handle.spec.diameter
        tip, end = np.asarray(ep.tools[:, i, 0], float), np.asarray(ep.tools[:, i, 1], float)
        rec.send_columns(
            f"{world}/{name}/shaft",
            indexes=index,
            columns=rr.LineStrips3D.columns(
                strips=np.stack([tip, end], axis=1), radii=np.full(n, 0.5 * d), colors=np.tile(TOOL, (n, 1))
            ),
        )
        rec.send_columns(
            f"{world}/{name}/tip",
            indexes=index,
            columns=rr.Points3D.columns(positions=tip, radii=np.full(n, 0.7 * d), colors=np.tile(TOOL, (n, 1))),
        )
        if n >= 2:
            rec.log(f"{world}/{name}/path", rr.LineStrips3D([tip], radii=0.0006, colors=TOOL_PATH), static=True)


def _log_bodies(rec: rr.RecordingStream, world: str, ep: EpisodeRecord, index: list, task: CompiledTask) -> None:
    """`{world}/loose_bodies`: every free body's centre per step, at its radius, labelled by its index."""
    centres = np.asarray(ep.bodies, float)
    n, k = centres.shape[:2]
    radii = np.array([b.radius for b in task.spec.task.bodies], float)
    rec.send_columns(
        f"{world}/loose_bodies",
        indexes=index,
        columns=rr.Points3D.columns(
            positions=centres.reshape(-1, 3), radii=np.tile(radii, n), colors=np.tile(rgba(BODY_RGBA[:3]), (n * k, 1))
        ).partition(np.full(n, k)),
    )
