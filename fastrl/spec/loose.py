"""LooseBodies: small free bodies on the plate and the cup they are dropped in."""

from __future__ import annotations

import math

from pydantic import Field

from .base import Pos, Strict


class LooseBody(Strict):
    """A small free sphere resting on the plate at `at` = [x, y] m."""

    at: tuple[float, float]
    radius: float = Field(0.004, ge=0.002, le=0.01, description="sphere radius (m)")


class Cup(Strict):
    """The marked cup on the plate the bodies go in."""

    at: tuple[float, float]
    radius: float = Field(0.016, ge=0.008, le=0.04, description="inner radius (m)")
    height: Pos = Field(0.01, le=0.04, description="wall height (m)")


def loose_errors(spec) -> list[tuple[tuple, str, object]]:
    """(loc, message, input) for a loose-bodies task without bodies or cup, or with them off the plate."""
    task, r = spec.task, spec.scene.radius
    if task.kind != "loose_bodies":
        extra = [name for name in ("bodies", "cup") if getattr(task, name)]
        return [(("task", name), f"only loose_bodies tasks take '{name}'", None) for name in extra]
    errors = []
    if not task.bodies:
        errors.append((("task", "bodies"), "loose_bodies needs at least one body", None))
    if task.cup is None:
        errors.append((("task", "cup"), "loose_bodies needs a cup", None))
    places = [(("task", "bodies", i, "at"), b.at, b.radius) for i, b in enumerate(task.bodies)]
    places += [(("task", "cup", "at"), task.cup.at, task.cup.radius)] if task.cup else []
    for loc, at, size in places:
        if math.hypot(*at) + size > r - 0.02:
            errors.append(
                (loc, f"[{at[0]}, {at[1]}] is too near the shell: keep within {r - 0.02 - size:.3f} m", list(at))
            )
    return errors
