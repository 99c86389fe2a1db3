"""The abdomen scene: the abdominal wall as a dome over the posterior wall, a trocar, and anatomy meshes."""

from __future__ import annotations

import mujoco
import numpy as np

from ..spec.anatomy import organ_mesh
from ..spec.models import AbdomenScene
from .dome import WORLD_CONAFFINITY, WORLD_CONTYPE, add_floor, add_shell

WALL_RGBA = (0.86, 0.6, 0.55, 1.0)
FLOOR_RGBA = (0.6, 0.35, 0.33, 1.0)
TROCAR_RGBA = (0.2, 0.2, 0.22, 1.0)


def build_abdomen(spec: mujoco.MjSpec, scene: AbdomenScene) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Add posterior wall, abdominal wall, trocars and organs; return {portal: (point, rotation)}."""
    add_floor(spec, "posterior_wall", scene.radius, FLOOR_RGBA)
    portals = add_shell(spec, scene, WALL_RGBA, TROCAR_RGBA)
    for name, organ in scene.anatomy.items():
        verts, faces = organ_mesh(organ)
        spec.add_mesh(
            name=f"{name}_mesh",
            uservert=verts.ravel().tolist(),
            userface=faces.ravel().tolist(),
            inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,
        )
        spec.worldbody.add_geom(
            name=f"organ_{name}",
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=f"{name}_mesh",
            rgba=organ.rgba,
            contype=WORLD_CONTYPE,
            conaffinity=WORLD_CONAFFINITY,
        )
    return portals
