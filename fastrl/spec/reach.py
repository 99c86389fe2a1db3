"""Where a spec's scope can look: its portal, and why a target is out of its reach (derived from a TaskSpec)."""

from __future__ import annotations

import math

import numpy as np

from . import geometry as geo


def portal_of(spec):
    """The portal the scope goes through."""
    return next(p for p in spec.scene.portals if p.name == spec.scope.portal)


def cue_for(spec, avatar):
    """The avatar's own cue, else the task's."""
    return avatar.cue or spec.task.cue


def portal_point(spec) -> np.ndarray:
    """Where the scope's portal is (m)."""
    p = portal_of(spec)
    return geo.portal_frame(spec.scene.radius, p.azimuth, p.elevation, p.aim)[0]


def avatar_problem(spec, av) -> str | None:
    """Why an avatar is outside the dome or out of the scope's reach, or None."""
    r = spec.scene.radius
    if av.surface == "plate" and math.hypot(*av.at) > r - 0.01:
        return (
            f"target [{av.at[0]}, {av.at[1]}] is outside the dome: it is {math.hypot(*av.at):.3f} m from "
            f"the centre, the plate inside the shell ends at {r - 0.01:.3f} m"
        )
    if av.surface == "dome" and not 5.0 <= av.at[1] <= 88.0:
        return f"target elevation {av.at[1]} deg is outside the dome's inner surface (5 to 88 deg)"
    pos, _, _ = geo.avatar_pose(r, av.surface, av.at, av.heading_deg)
    return reach_problem(spec, pos, cue_for(spec, av))


def reach_problem(spec, pos: np.ndarray, cue) -> str | None:
    """Why the scope cannot view a target at `pos` under `cue`, or None."""
    p = portal_of(spec)
    point, rot = geo.portal_frame(spec.scene.radius, p.azimuth, p.elevation, p.aim)
    d = pos - point
    dist = float(np.linalg.norm(d))
    off = math.degrees(math.acos(np.clip(d @ rot[:, 2] / dist, -1, 1)))
    reach = spec.scope.pivot_limit_deg + spec.scope.optics_deg
    if off > reach:
        return (
            f"portal '{p.name}' cannot reach this target: it lies {off:.0f} deg off the portal axis, "
            f"the scope reaches {reach:.0f} deg (pivot limit + optics angle)"
        )
    far = spec.scope.insertion[1] + 0.5 * (cue.distance[0] + cue.distance[1])
    if dist > far:
        return (
            f"portal '{p.name}' cannot reach this target: it is {dist:.3f} m away, the scope holds it "
            f"at mid viewing distance only up to {far:.3f} m (insertion + viewing distance)"
        )
    if dist < cue.distance[0]:
        return f"target is {dist:.3f} m from portal '{p.name}', closer than the cue's minimum distance"
    return None
