"""Instruments besides the arthroscope: a palpation probe or a grasper through a portal of their own."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from .base import Pos, Strict, _fail
from .shaft import Shaft


class InstrumentStart(Strict):
    """Initial portal coordinates of an instrument."""

    pitch_deg: float = 0.0
    yaw_deg: float = 0.0
    insertion: float = 0.03
    roll_deg: float = 0.0
    jaw_deg: float = Field(0.0, ge=0, description="grasper: initial jaw opening (deg)")


class Instrument(Shaft):
    """A probe (palpation hook) or grasper: shaft through a portal, the same exact fulcrum chain as the scope."""

    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    kind: Literal["probe", "grasper"]
    diameter: float = Field(0.003, gt=0.001, le=0.02)
    jaw_deg: float = Field(60.0, gt=0, le=120, description="grasper: widest jaw opening (deg)")
    touch: Pos = Field(0.004, le=0.05, description="the tip touches a target within this distance of it (m)")
    start: InstrumentStart = InstrumentStart()

    @model_validator(mode="after")
    def _jaw(self):
        if self.start.jaw_deg > self.jaw_deg:
            _fail("start.jaw_deg", f"start jaw {self.start.jaw_deg} deg is wider than jaw_deg {self.jaw_deg}")
        return self

    @property
    def coordinates(self) -> int:
        """How many portal coordinates drive it: pitch, yaw, insertion, roll (and the grasper's jaw)."""
        return 5 if self.kind == "grasper" else 4


def instrument_errors(spec) -> list[tuple[tuple, str, object]]:
    """(loc, message, input) for instruments in unknown or taken portals, or out of reach of their targets."""
    import math

    import numpy as np

    from ..terms import OBSERVATION_TERMS, REWARD_FEATURES
    from . import geometry as geo

    errors = [
        (("observation", "extra", i), f"'{name}' observes the instruments: the spec declares none", name)
        for i, name in enumerate(spec.observation.extra)
        if "instruments" in OBSERVATION_TERMS[name].needs and not spec.instruments
    ]
    errors += [
        (("reward", "features", name), f"'{name}' scores the instruments: the spec declares none", name)
        for name in spec.reward.features
        if "instruments" in REWARD_FEATURES[name].needs and not spec.instruments
    ]
    portals = {p.name: p for p in spec.scene.portals}
    taken = {spec.scope.portal: "the scope"}
    for i, inst in enumerate(spec.instruments):
        if inst.portal not in portals:
            errors.append(
                (
                    ("instruments", i, "portal"),
                    f"no portal named '{inst.portal}' (portals: {', '.join(portals)})",
                    inst.portal,
                )
            )
            continue
        if inst.portal in taken:
            errors.append(
                (("instruments", i, "portal"), f"portal '{inst.portal}' is taken by {taken[inst.portal]}", inst.portal)
            )
        taken[inst.portal] = f"instrument '{inst.name}'"
    names = [inst.name for inst in spec.instruments]
    if len(set(names)) != len(names):
        errors.append((("instruments",), f"instrument names must be unique, got {names}", names))
    kinds = {inst.kind for inst in spec.instruments}
    needs = {"triangulation": "probe", "loose_bodies": "grasper"}.get(spec.task.kind)
    if needs and needs not in kinds:
        errors.append((("task", "kind"), f"{spec.task.kind} needs an instrument of kind '{needs}'", spec.task.kind))
    if errors or not needs:
        return errors
    inst = next(x for x in spec.instruments if x.kind == needs)
    p = portals[inst.portal]
    point, rot = geo.portal_frame(spec.scene.radius, p.azimuth, p.elevation, p.aim)
    for i, av in enumerate(spec.task.avatars):
        pos, _, _ = geo.avatar_pose(spec.scene.radius, av.surface, av.at, av.heading_deg)
        d = pos - point
        dist = float(np.linalg.norm(d))
        off = math.degrees(math.acos(np.clip(d @ rot[:, 2] / dist, -1, 1)))
        if off > inst.pivot_limit_deg or dist > inst.insertion[1]:
            errors.append(
                (
                    ("task", "avatars", i, "at"),
                    f"instrument '{inst.name}' cannot reach this target from portal '{p.name}': it is {dist:.3f} m "
                    f"away and {off:.0f} deg off the portal axis "
                    f"(reach {inst.insertion[1]} m, {inst.pivot_limit_deg:g} deg)",
                    list(av.at),
                )
            )
    return errors
