"""The dome tasks (ImageCentring, Periscoping, TraceLines): avatars on the dome or the plate, moved by the jitter."""

from __future__ import annotations

import numpy as np

from ..spec import geometry as geo
from .task import Task


class DomeTask(Task):
    """The scope's cue machine over the avatars of a FAST dome; each episode moves them by the spec's jitter."""

    def episode_targets(self, rng: np.random.Generator) -> None:
        """The spec's avatars, each moved on its surface by up to the jitter (plate: m, dome: degrees)."""
        super().episode_targets(rng)
        spec, t = self.compiled.spec, self.compiled.targets
        jm, jd = spec.task.jitter
        if jm == 0 and jd == 0:
            return
        r, m = spec.scene.radius, self.model
        for i in range(len(t)):
            noise = rng.uniform(-1.0, 1.0, 2)
            surface = "plate" if t.on_plate[i] else "dome"
            at = t.at[i] + noise * (jm if t.on_plate[i] else jd)
            pos, fwd, up = geo.avatar_pose(r, surface, at, t.heading[i])
            self.t_pos[i], self.t_fwd[i], self.t_up[i] = pos, fwd, up
            self.t_quat[i] = geo.mat_to_quat(geo.avatar_rotation(fwd, up))
            disk, mark = self.compiled.avatar_geoms[i]
            m.geom_pos[disk] = pos
            m.geom_pos[mark] = pos + 0.9 * t.size * up + 0.0002 * fwd
            m.geom_quat[disk] = m.geom_quat[mark] = self.t_quat[i]
