"""A render-only copy of a task's model whose fixed geoms are triangle meshes: the frames, drawn faster.

llvmpipe (software GL) pays per triangle it sets up, and more for MuJoCo's builtin shapes (quads, three display
lists a capsule) than for a mesh of the same triangles. The world's fixed boxes, cylinders and capsules become
meshes of the triangles MuJoCo would draw, in the world frame; geom ids stay the env's, so segmentation and the
view-cone cull are unchanged, and the moving geoms (scope, instruments, avatars) are drawn as built.
"""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np

from ..model.compiler import CompiledTask, build_mjspec

_G = mujoco.mjtGeom
_CONVERTED = [int(t) for t in (_G.mjGEOM_BOX, _G.mjGEOM_CYLINDER, _G.mjGEOM_CAPSULE)]
_F = np.float32


# ---- MuJoCo's builtin shapes (render_context.c), as the triangles OpenGL draws from its quads ------------------
def _quads(quads: list) -> list:
    """Each quad's two triangles, split as Mesa splits GL_QUADS: (1, 2, 4) and (2, 3, 4)."""
    return [t for a, b, c, d in quads for t in ((a, b, d), (b, c, d))]


def _az(j: int, ns: int) -> np.float32:
    """The azimuth of slice j of ns, rounded as MuJoCo rounds it (double, then float)."""
    return _F(2.0 * math.pi * j / ns)


def _sphere_vertex(az, el, sign) -> tuple:
    """A vertex and its normal on a unit half sphere whose equator sits at z = sign."""
    v = (np.cos(az) * np.cos(el), np.sin(az) * np.cos(el), _F(sign) + np.sin(el))
    return v, (v[0], v[1], v[2] - _F(sign))


def _half_sphere(sign: int, ns: int, nt: int) -> list:
    """halfSphere(): pole triangles, then quads, in the order and winding MuJoCo emits them."""
    tris, quads = [], []
    el = _F(math.pi / 2.0 * sign * (nt - 1) / nt)
    for j in range(ns):
        a1, a2 = _az(j, ns), _az(j + 1, ns)
        p1, p2 = _sphere_vertex(a1, el, sign), _sphere_vertex(a2, el, sign)
        pole = ((_F(0), _F(0), _F(2 * sign)), (_F(0), _F(0), _F(sign)))
        tris.append((p1, p2, pole) if sign > 0 else (pole, p2, p1))
    for i in range(nt - 1):
        e1, e2 = _F(math.pi / 2.0 * sign * i / nt), _F(math.pi / 2.0 * sign * (i + 1) / nt)
        for j in range(ns):
            a1, a2 = _az(j, ns), _az(j + 1, ns)
            q = (_sphere_vertex(a1, e1, sign), _sphere_vertex(a2, e1, sign))
            q += (_sphere_vertex(a2, e2, sign), _sphere_vertex(a1, e2, sign))
            quads.append(q if sign > 0 else q[::-1])
    return tris + _quads(quads)


def _disk(sign: int, ns: int, nt: int) -> list:
    """disk(): a unit disk at z = sign facing out, pole triangles then quads."""
    n = (_F(0), _F(0), _F(sign))

    def vertex(az, r):
        return (np.cos(az) * r, np.sin(az) * r, _F(sign)), n

    tris, quads = [], []
    for j in range(ns):
        a1, a2 = _az(j, ns), _az(j + 1, ns)
        t = (vertex(a1, _F(1) / _F(nt)), vertex(a2, _F(1) / _F(nt)), ((_F(0), _F(0), _F(sign)), n))
        tris.append(t if sign > 0 else t[::-1])
    for i in range(nt - 1):
        r1, r2 = _F(i + 1) / _F(nt), _F(i + 2) / _F(nt)
        for j in range(ns):
            a1, a2 = _az(j, ns), _az(j + 1, ns)
            q = (vertex(a1, r2), vertex(a2, r2), vertex(a2, r1), vertex(a1, r1))
            quads.append(q if sign > 0 else q[::-1])
    return tris + _quads(quads)


def _tube(ns: int, nt: int) -> list:
    """cylinder(): the open unit cylinder from z = -1 to 1."""

    def vertex(az, h):
        x, y = np.cos(az), np.sin(az)
        r = np.sqrt(x * x + y * y)
        return (x, y, h), (x / r, y / r, _F(0))

    quads = []
    for i in range(nt):
        h1, h2 = _F(2 * i) / _F(nt) - _F(1), _F(2 * (i + 1)) / _F(nt) - _F(1)
        for j in range(ns):
            a1, a2 = _az(j, ns), _az(j + 1, ns)
            quads.append((vertex(a1, h1), vertex(a2, h1), vertex(a2, h2), vertex(a1, h2)))
    return _quads(quads)


def _face_point(axis: int, sign: int, p, q) -> tuple:
    """A point of the unit box's face normal to `axis` on side `sign`, at in-face coordinates p, q."""
    v = [p, q]
    v.insert(axis, _F(sign))
    return tuple(v)


def _box(nq: int) -> list:
    """The builtin box: every face a grid of nq x nq quads."""
    d, quads = _F(2.0 / nq), []
    for x in range(nq):
        for y in range(nq):
            a0, a1, b0, b1 = d * x - 1, d * (x + 1) - 1, d * y - 1, d * (y + 1) - 1
            for axis, sign in ((2, 1), (2, -1), (0, 1), (0, -1), (1, -1), (1, 1)):
                forward = sign == (-1 if axis == 1 else 1)  # top, right, front; the others wind backwards
                u = ((a0, b0), (a1, b0), (a1, b1), (a0, b1)) if forward else ((a0, b1), (a1, b1), (a1, b0), (a0, b0))
                n = tuple(_F(sign) if k == axis else _F(0) for k in range(3))
                quads.append(tuple((_face_point(axis, sign, p, q), n) for p, q in u))
    return _quads(quads)


def _array(tris: list) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of (vertex, normal) pairs as (T, 3, 3) vertex and normal arrays."""
    a = np.array([[[*v, *n] for v, n in t] for t in tris], dtype=np.float64)
    return a[..., :3], a[..., 3:]


def unit_shapes(model: mujoco.MjModel) -> dict:
    """The builtin shapes at the model's visual quality: name -> (vertices, normals), each (T, 3, 3).

    A capsule's tube is one ring of quads, not numstacks: the surface is the same, only the lighting, computed
    at the vertices, is interpolated over longer quads (0.25% of the pixels differ, 0.002% by more than 8 levels).
    """
    q = model.vis.quality
    ns, nt = q.numslices, q.numstacks
    return {
        "box": _array(_box(q.numquads)),
        "cylinder": _array(_disk(-1, ns, nt // 2) + _tube(ns, nt) + _disk(1, ns, nt // 2)),
        "tube": _array(_tube(ns, 1)),  # a capsule's straight side in one ring: the same surface, fewer triangles
        "top": _array(_half_sphere(1, ns, nt // 2)),
        "bottom": _array(_half_sphere(-1, ns, nt // 2)),
    }


def geom_triangles(model: mujoco.MjModel, data: mujoco.MjData, g: int, shapes: dict, bottom: bool = True) -> tuple:
    """Geom g's triangles in the world frame as the renderer draws them: vertices and unit normals, (T, 3, 3).

    bottom=False leaves out a capsule's bottom half sphere (where another capsule's top one covers it).
    """
    r, h = model.geom_size[g, 0], model.geom_size[g, 1]
    kind = model.geom_type[g]
    if kind == _G.mjGEOM_BOX:
        parts = [("box", model.geom_size[g], 0.0)]
    elif kind == _G.mjGEOM_CYLINDER:
        parts = [("cylinder", (r, r, h), 0.0)]
    else:  # capsule: the open tube, then the two half spheres moved to its ends
        parts = [("tube", (r, r, h), 0.0), ("top", (r, r, r), h - r), ("bottom", (r, r, r), r - h)][
            : 3 if bottom else 2
        ]
    pos = data.geom_xpos[g].astype(_F).astype(float)  # the float pose the renderer gets (mjvGeom)
    rot = data.geom_xmat[g].astype(_F).astype(float).reshape(3, 3)
    verts, normals = [], []
    for name, scale, dz in parts:
        v, n = shapes[name]
        scale = np.asarray(scale, _F).astype(float)
        n = n / scale  # the inverse transpose of the scaling, as GL_NORMALIZE then normalises
        verts.append((v * scale + (0.0, 0.0, dz)) @ rot.T + pos)
        normals.append((n / np.linalg.norm(n, axis=-1, keepdims=True)) @ rot.T)
    return np.concatenate(verts), np.concatenate(normals)


def fixed_geoms(model: mujoco.MjModel, moving: np.ndarray) -> np.ndarray:
    """The world's geoms drawn as boxes, cylinders or capsules that never move (all but those in `moving`)."""
    fixed = (model.geom_bodyid == 0) & np.isin(model.geom_type, _CONVERTED) & (model.geom_matid < 0)
    fixed[np.asarray(moving, int)] = False
    return np.flatnonzero(fixed)


def covered_ends(model: mujoco.MjModel, data: mujoco.MjData, fixed: np.ndarray) -> set[int]:
    """Capsules whose bottom end is another capsule's top end, alike in radius and colour (a polyline's joints).

    The top half sphere there already draws the joint's outer side; the bottom one lies inside or on the union.
    """
    caps = [g for g in fixed if model.geom_type[g] == _G.mjGEOM_CAPSULE]
    ends = {}
    for g in caps:
        axis = data.geom_xmat[g].reshape(3, 3)[:, 2] * model.geom_size[g, 1]
        look = (model.geom_size[g, 0], *model.geom_rgba[g])
        ends[g] = (tuple(np.round(data.geom_xpos[g] + axis, 9)), tuple(np.round(data.geom_xpos[g] - axis, 9)), look)
    tops = {(top, look) for top, _, look in ends.values()}
    return {g for g, (_, bottom, look) in ends.items() if (bottom, look) in tops}


_CACHE: dict[str, mujoco.MjModel] = {}


def lean_model(task: CompiledTask, model: mujoco.MjModel, fixed: np.ndarray) -> mujoco.MjModel:
    """The task's model with each fixed geom a mesh of its triangles in the world frame, same ids (cached per task)."""
    key = task.spec.model_dump_json()
    if key not in _CACHE:
        spec, _ = build_mjspec(task.spec)
        elements = list(spec.geoms)
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        shapes, covered = unit_shapes(model), covered_ends(model, data, fixed)
        for g in fixed:
            v, n = geom_triangles(model, data, g, shapes, bottom=g not in covered)
            index = np.arange(3 * len(v), dtype=np.int32)
            spec.add_mesh(
                name=f"lean_{g}",
                uservert=v.ravel(),
                usernormal=n.ravel(),
                usertexcoord=[0.0, 0.0],  # with texture coordinates MuJoCo draws the normals given, as they are
                userface=index,
                userfacenormal=index,
                userfacetexcoord=np.zeros_like(index),
                inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,
            )
            e = elements[g]
            e.type, e.meshname = _G.mjGEOM_MESH, f"lean_{g}"
            e.fromto = [np.nan] * 6
            e.pos, e.quat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
            e.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT  # not the euler angles etc. it was built with
        lean = spec.compile()
        lean.stat.center[:] = model.stat.center  # the clipping planes follow the scene's extent, as compiled
        lean.stat.extent = model.stat.extent
        _CACHE.clear()
        _CACHE[key] = lean
    return copy.copy(_CACHE[key])


class LeanScene:
    """The lean model and its data, given the env's poses, colours and lighting before each frame."""

    def __init__(self, *, task: CompiledTask, model: mujoco.MjModel):
        fixed = fixed_geoms(model, task.avatar_geoms.ravel())
        self.model = lean_model(task, model, fixed)
        self.data = mujoco.MjData(self.model)
        mujoco.mj_kinematics(self.model, self.data)  # the meshes' poses: fixed
        self.moving = np.setdiff1d(np.arange(model.ngeom), fixed)
        lm, h, lh = self.model, model.vis.headlight, self.model.vis.headlight  # what randomised looks change:
        self.copies = [(lm.geom_rgba, model.geom_rgba), (lm.light_diffuse, model.light_diffuse)]
        self.copies += [(lh.ambient, h.ambient), (lh.diffuse, h.diffuse), (lh.specular, h.specular)]

    def sync(self, data: mujoco.MjData) -> mujoco.MjData:
        """Copy the env's geom poses, colours, camera and lights into the lean model and data; the data to draw."""
        ld, g = self.data, self.moving
        ld.geom_xpos[g], ld.geom_xmat[g] = data.geom_xpos[g], data.geom_xmat[g]
        ld.cam_xpos[:], ld.cam_xmat[:] = data.cam_xpos, data.cam_xmat
        ld.light_xpos[:], ld.light_xdir[:] = data.light_xpos, data.light_xdir
        for mine, env in self.copies:
            mine[:] = env
        return ld
