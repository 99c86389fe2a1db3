"""The instruments of an episode in Rerun: each shaft and tip per step, and each tip's path."""

from __future__ import annotations

import numpy as np
import rerun as rr

from ..data.episode import EpisodeRecord
from ..model.compiler import CompiledTask
from .shapes import rgba

TOOL = rgba((0.75, 0.72, 0.45))
TOOL_PATH = rgba((0.95, 0.6, 0.2))


def log_instruments(rec: rr.RecordingStream, world: str, ep: EpisodeRecord, index: list, task: CompiledTask) -> None:
    """`{world}/{name}/shaft` and `/tip` on the step timelines, `/path` static; nothing without instruments."""
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
