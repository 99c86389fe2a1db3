"""Anatomy geometry of a spec: parametric ellipsoids made in code, or OBJ/STL files read by MuJoCo; landmark poses.

The one MuJoCo import of the spec layer: validating a spec (organ inside the cavity, landmark in reach) needs the
vertices of its mesh files as MuJoCo reads them (pyproject.toml names this exception in the import contracts).
"""

from __future__ import annotations

import math
import os
from functools import lru_cache

import mujoco
import numpy as np


class MeshError(ValueError):
    """A mesh file that is missing or that MuJoCo cannot read."""


def ellipsoid_mesh(centre, size, bumps: float = 0.0, n_lat: int = 14, n_lon: int = 28) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and outward triangles (F, 3) of an ellipsoid, its surface waved by `bumps` (bowel loops)."""
    lat = np.linspace(-0.5 * math.pi, 0.5 * math.pi, n_lat + 1)[1:-1]
    lon = np.linspace(0.0, 2 * math.pi, n_lon, endpoint=False)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    dirs = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1).reshape(-1, 3)
    dirs = np.vstack([[0.0, 0.0, -1.0], dirs, [0.0, 0.0, 1.0]])
    wave = 1.0 + bumps * np.sin(5 * np.arctan2(dirs[:, 1], dirs[:, 0])) * np.sin(3 * math.pi * dirs[:, 0])
    verts = np.asarray(centre, float) + dirs * np.asarray(size, float) * np.minimum(wave, 1.0)[:, None]
    faces = []
    ring = lambda i, j: 1 + i * n_lon + (j % n_lon)  # noqa: E731 - vertex index on latitude ring i
    for j in range(n_lon):
        faces.append([0, ring(0, j + 1), ring(0, j)])
        top = len(verts) - 1
        faces.append([top, ring(n_lat - 2, j), ring(n_lat - 2, j + 1)])
        for i in range(n_lat - 2):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            faces += [[a, b, d], [a, d, c]]
    return verts, np.array(faces, np.int32)


@lru_cache(maxsize=32)
def _read_mesh(path: str, scale: float, mtime: float) -> tuple[np.ndarray, np.ndarray]:
    """World vertices and faces of a mesh file, read and compiled by MuJoCo (cached per file version)."""
    spec = mujoco.MjSpec()
    spec.add_mesh(name="m", file=path, scale=[scale] * 3)
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m")
    try:
        model = spec.compile()
    except ValueError as e:
        raise MeshError(f"cannot read mesh {path}: {str(e).splitlines()[0].removeprefix('Error: ')}") from None
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    a, n = model.mesh_vertadr[0], model.mesh_vertnum[0]
    verts = data.geom_xpos[0] + model.mesh_vert[a : a + n] @ data.geom_xmat[0].reshape(3, 3).T
    fa, fn = model.mesh_faceadr[0], model.mesh_facenum[0]
    return verts, model.mesh_face[fa : fa + fn].copy()


def organ_mesh(organ) -> tuple[np.ndarray, np.ndarray]:
    """World vertices and faces of an organ of the spec (its mesh file, else its ellipsoid)."""
    if organ.mesh is None:
        return ellipsoid_mesh(organ.centre, organ.size, organ.bumps)
    path = organ.mesh
    if not os.path.isfile(path):
        raise MeshError(f"mesh file {path} does not exist")
    if not path.lower().endswith((".obj", ".stl")):
        raise MeshError(f"mesh file {path} is not an OBJ or STL file")
    return _read_mesh(path, float(organ.scale), os.path.getmtime(path))


def organ_vertices(organ) -> np.ndarray:
    """World vertices (V, 3) of an organ."""
    return organ_mesh(organ)[0]


def landmark_pose(organ, portal_point) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The organ's vertex that faces the portal most, the direction back to the portal, and image up there."""
    verts = organ_vertices(organ)
    centre = verts.mean(axis=0)
    toward = np.asarray(portal_point, float) - centre
    pos = verts[np.argmax(verts @ (toward / np.linalg.norm(toward)))]
    fwd = np.asarray(portal_point, float) - pos
    fwd /= np.linalg.norm(fwd)
    up = np.array([0.0, 0.0, 1.0]) if abs(fwd[2]) < 0.95 else np.array([1.0, 0.0, 0.0])
    up = up - (up @ fwd) * fwd
    return pos, fwd, up / np.linalg.norm(up)


def anatomy_vertices(scene) -> np.ndarray:
    """All anatomy vertices of an abdomen scene, stacked (for the safety score)."""
    return np.vstack([organ_vertices(o) for o in scene.anatomy.values()])
