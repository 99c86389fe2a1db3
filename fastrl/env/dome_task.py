"""The dome tasks (ImageCentring, Periscoping, TraceLines): avatars on the dome or the plate, moved by the resets."""

from __future__ import annotations

import numpy as np

from ..spec import geometry as geo
from ..terms import EpisodeStart
from .task import Task


class DomeTask(Task):
    """The scope's cue machine over the avatars of a FAST dome, placed where the episode's start puts them."""

    def episode_targets(self, start: EpisodeStart) -> None:
        """The avatars where the reset terms put them on their surfaces (the spec's, if they moved none)."""
        super().episode_targets(start)
        t, m = self.compiled.targets, self.model
        if np.array_equal(start.at, t.at):
            return
        r = self.compiled.spec.scene.radius
        for i in range(len(t)):
            pos, fwd, up = geo.avatar_pose(r, "plate" if t.on_plate[i] else "dome", start.at[i], t.heading[i])
            self.t_pos[i], self.t_fwd[i], self.t_up[i] = pos, fwd, up
            self.t_quat[i] = geo.mat_to_quat(geo.avatar_rotation(fwd, up))
            disk, mark = self.compiled.avatar_geoms[i]
            m.geom_pos[disk] = pos
            m.geom_pos[mark] = pos + 0.9 * t.size * up + 0.0002 * fwd
            m.geom_quat[disk] = m.geom_quat[mark] = self.t_quat[i]
