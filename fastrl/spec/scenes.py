"""Scene kinds of a spec: the FAST dome, and the abdomen with its anatomy; portals through their walls."""

from __future__ import annotations

import stat
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, Field, field_validator, model_validator

from .anatomy import MeshError, organ_vertices
from .base import NonNeg, Pos, Strict, _raise
from .limits import MAX_MESH_BYTES


class Portal(Strict):
    """A hole in the dome shell through which the scope pivots."""

    name: str
    azimuth: float = Field(description="degrees about +z from +x")
    elevation: float = Field(ge=0, le=85, description="degrees above the plate")
    aim: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="point the shaft aims at when pitch = yaw = 0 (m)"
    )
    radius: Pos = Field(0.012, description="radius of the hole (m)")


def _unique_names(portals: list[Portal]) -> list[Portal]:
    """Portal names must be unique."""
    names = [p.name for p in portals]
    if len(set(names)) != len(names):
        raise ValueError(f"portal names must be unique, got {names}")
    return portals


Portals = Annotated[list[Portal], AfterValidator(_unique_names)]


class DomeScene(Strict):
    """The FAST dome: a hemispherical shell over a base plate."""

    kind: Literal["fast_dome"] = "fast_dome"
    radius: float = Field(0.12, ge=0.05, le=0.5, description="inner radius of the shell (m)")
    thickness: float = Field(0.004, gt=0, le=0.02, description="shell thickness (m)")
    rings: int = Field(7, ge=3, le=40, description="shell tiles from rim to crown")
    sectors: int = Field(18, ge=6, le=96, description="shell tiles around")
    portals: Portals = Field(min_length=1)


class Organ(Strict):
    """One piece of anatomy: a parametric ellipsoid, or a mesh file (OBJ or STL, metres, world frame)."""

    centre: tuple[float, float, float] = Field((0.0, 0.0, 0.03), description="ellipsoid centre (m)")
    size: tuple[Pos, Pos, Pos] = Field((0.03, 0.03, 0.02), description="ellipsoid semi-axes (m)")
    bumps: NonNeg = Field(0.0, le=0.5, description="relative amplitude of a wavy surface (bowel loops)")
    mesh: str | None = Field(None, description="OBJ or STL file, relative to the spec file; replaces the ellipsoid")
    scale: Pos = Field(1.0, description="mesh file units to metres")
    rgba: tuple[float, float, float, float] = (0.55, 0.2, 0.15, 1.0)

    @field_validator("mesh")
    @classmethod
    def _resolve(cls, v, info):
        base = (info.context or {}).get("base")
        if v is None or base is None:
            return v
        path = Path(v) if Path(v).is_absolute() else base / v
        try:
            info_ = path.stat()
        except (OSError, RuntimeError):
            return str(path.absolute())  # missing: the scene reports it
        if not stat.S_ISREG(info_.st_mode):
            raise ValueError(f"mesh {v} is not a regular file")
        if info_.st_size > MAX_MESH_BYTES:
            raise ValueError(f"mesh {v} is {info_.st_size:,} bytes, at most {MAX_MESH_BYTES:,} are read")
        return str(path.resolve())


def _default_anatomy() -> dict[str, Organ]:
    """Liver lobes, falciform ligament, gallbladder and bowel of an insufflated abdomen (x cranial, y left)."""
    return {
        "right_lobe": Organ(centre=(0.075, -0.045, 0.035), size=(0.05, 0.06, 0.035), rgba=(0.5, 0.16, 0.12, 1)),
        "left_lobe": Organ(centre=(0.07, 0.05, 0.03), size=(0.04, 0.045, 0.024), rgba=(0.55, 0.19, 0.14, 1)),
        "falciform": Organ(centre=(0.055, 0.0, 0.09), size=(0.04, 0.002, 0.035), rgba=(0.9, 0.82, 0.6, 1)),
        "gallbladder": Organ(centre=(0.03, -0.065, 0.02), size=(0.025, 0.012, 0.012), rgba=(0.3, 0.5, 0.2, 1)),
        "bowel": Organ(centre=(-0.045, 0.0, 0.021), size=(0.075, 0.1, 0.02), bumps=0.25, rgba=(0.85, 0.55, 0.5, 1)),
    }


class AbdomenScene(Strict):
    """An insufflated abdomen: the abdominal wall as a dome over the posterior wall, with anatomy inside."""

    kind: Literal["abdomen"]
    radius: float = Field(0.15, ge=0.05, le=0.5, description="inner radius of the abdominal wall (m)")
    thickness: float = Field(0.01, gt=0, le=0.05, description="wall thickness (m)")
    rings: int = Field(7, ge=3, le=40, description="wall tiles from flank to top")
    sectors: int = Field(18, ge=6, le=96, description="wall tiles around")
    portals: Portals = Field(min_length=1, description="trocars through the wall")
    anatomy: dict[str, Organ] = Field(default_factory=_default_anatomy, min_length=1)

    @model_validator(mode="after")
    def _inside(self):
        errors = []
        for name, organ in self.anatomy.items():
            field = "mesh" if organ.mesh else "size"
            try:
                verts = organ_vertices(organ)
            except MeshError as e:
                errors.append((("anatomy", name, "mesh"), str(e), organ.mesh))
                continue
            out = np.linalg.norm(verts, axis=1) > self.radius + 1e-6
            low = verts[:, 2] < -1e-6
            if out.any() or low.any():
                far = float(np.linalg.norm(verts, axis=1).max())
                where = (
                    f"reaches {far:.3f} m from the centre, past the wall at {self.radius:.3f} m"
                    if out.any()
                    else f"goes {-verts[:, 2].min():.3f} m below the posterior wall (z = 0)"
                )
                errors.append((("anatomy", name, field), f"{name} is outside the cavity: it {where}", organ.mesh))
        _raise(errors)
        return self


Scene = Annotated[DomeScene | AbdomenScene, Field(discriminator="kind")]
