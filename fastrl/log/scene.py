"""The static 3D scene of a compiled task: dome or abdominal wall, plate, portals, anatomy, avatars, line."""

from __future__ import annotations

import numpy as np
import rerun as rr

from ..model.abdomen import FLOOR_RGBA, TROCAR_RGBA, WALL_RGBA
from ..model.compiler import CompiledTask
from ..model.dome import PLATE_RGBA, PORTAL_RGBA, SHELL_RGBA
from ..model.loose import CUP_MARK_RGBA, CUP_RGBA
from ..model.targets import LINE_RGBA
from ..spec import geometry as geo
from ..spec.anatomy import organ_mesh
from .shapes import disk, hemisphere, rgba, ring

AVATAR_RGBA = (0.8, 0.62, 0.42)  # muted: the current avatar is drawn per episode in cue colours
SHELL_ALPHA = 0.35


def log_scene(rec: rr.RecordingStream, task: CompiledTask, root: str = "world") -> None:
    """Log the task's static scene under `{root}/scene` and Z-up view coordinates on `root`."""
    rec.log(root, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    scene = task.spec.scene
    base = f"{root}/scene"
    if getattr(scene, "kind", None) == "fast_dome":
        _log_dome(rec, base, scene, task.spec.scope.portal)
    elif getattr(scene, "kind", None) == "abdomen":
        _log_dome(rec, base, scene, task.spec.scope.portal, WALL_RGBA, FLOOR_RGBA, TROCAR_RGBA)
        _log_anatomy(rec, base, scene)
    _log_targets(rec, base, task)
    if getattr(task.spec.task, "cup", None) is not None:
        _log_cup(rec, base, task.spec.task.cup)


def _log_cup(rec: rr.RecordingStream, base: str, cup) -> None:
    """LooseBodies' cup: its marked floor and its wall as rings at the floor and the rim."""
    centre = np.array([*cup.at, 0.0])
    fv, ft = disk(cup.radius, z=0.0005)
    rec.log(
        f"{base}/cup/floor",
        rr.Mesh3D(
            vertex_positions=fv + centre,
            triangle_indices=ft,
            albedo_factor=rgba(CUP_MARK_RGBA),
            vertex_normals=np.tile([0.0, 0.0, 1.0], (len(fv), 1)),
        ),
        static=True,
    )
    up = np.array([0.0, 0.0, 1.0])
    rims = [ring(centre + [0.0, 0.0, h], up, cup.radius, n=48) for h in (0.0, 0.5 * cup.height, cup.height)]
    rec.log(f"{base}/cup/wall", rr.LineStrips3D(rims, radii=0.0008, colors=rgba(CUP_RGBA)), static=True)


def default_eye(task: CompiledTask) -> tuple[tuple, tuple]:
    """3D-view eye (position, look target): above the dome, beside the scope's portal."""
    p = np.asarray(task.portal_point, float)
    r = float(np.linalg.norm(p)) or 0.12
    flat = np.hypot(p[0], p[1]) or 1.0
    outward, side = np.array([p[0], p[1], 0.0]) / flat, np.array([p[1], -p[0], 0.0]) / flat
    position = 2.1 * r * (0.6 * outward + 0.8 * side) + np.array([0.0, 0.0, 2.2 * r])
    return tuple(position), (0.0, 0.0, 0.1 * r)


def _log_anatomy(rec: rr.RecordingStream, base: str, scene) -> None:
    """Each organ's mesh in its colour, named by its entity path."""
    for name, organ in scene.anatomy.items():
        verts, faces = organ_mesh(organ)
        rec.log(
            f"{base}/anatomy/{name}",
            rr.Mesh3D(vertex_positions=verts, triangle_indices=faces.astype(np.uint32), albedo_factor=rgba(organ.rgba)),
            static=True,
        )


def _log_dome(
    rec: rr.RecordingStream,
    base: str,
    scene,
    scope_portal: str,
    shell_rgba=SHELL_RGBA,
    plate_rgba=PLATE_RGBA,
    portal_rgba=PORTAL_RGBA,
) -> None:
    """Shell with holes at the portals, base plate, and a labelled ring per portal."""
    r = scene.radius
    holes = [(geo.sphere_point(1.0, p.azimuth, p.elevation), 1.4 * p.radius / r) for p in scene.portals]
    verts, normals, tris = hemisphere(r, holes)
    # Only back faces: from outside, the near wall is culled and the inside of the dome shows.
    rec.log(
        f"{base}/shell",
        rr.Mesh3D(
            vertex_positions=verts,
            vertex_normals=normals,
            triangle_indices=tris,
            albedo_factor=rgba(shell_rgba, SHELL_ALPHA),
            face_rendering=rr.components.MeshFaceRendering.Back,
        ),
        static=True,
    )
    rim = ring(np.zeros(3), np.array([0.0, 0.0, 1.0]), r + scene.thickness, n=96)
    rec.log(
        f"{base}/shell/rim",
        rr.LineStrips3D([rim], radii=0.0008, colors=rgba(shell_rgba) // 2 + 64),
        static=True,
    )
    pv, pt = disk(r + 0.03, z=-0.0003)
    rec.log(
        f"{base}/plate",
        rr.Mesh3D(
            vertex_positions=pv,
            triangle_indices=pt,
            albedo_factor=rgba(plate_rgba),
            vertex_normals=np.tile([0.0, 0.0, 1.0], (len(pv), 1)),
        ),
        static=True,
    )
    strips, labels = [], []
    for p in scene.portals:
        point = geo.sphere_point(r, p.azimuth, p.elevation)
        strips.append(ring(point, point, 1.4 * p.radius))
        labels.append(f"{p.name} (scope)" if p.name == scope_portal else p.name)
    rec.log(
        f"{base}/portals",
        rr.LineStrips3D(strips, radii=0.0012, colors=rgba(portal_rgba), labels=labels, show_labels=True),
        static=True,
    )


def _log_targets(rec: rr.RecordingStream, base: str, task: CompiledTask) -> None:
    """Avatars as points with an 'up' arrow and index label; TraceLines' line as a strip."""
    t = task.targets
    n = len(t)
    if n:
        rec.log(
            f"{base}/avatars",
            rr.Points3D(
                t.pos,
                radii=0.7 * t.size,
                colors=rgba(AVATAR_RGBA, 1.0),
                labels=[str(i) for i in range(n)],
                show_labels=_spread(t.pos) > 0.02,
            ),
            static=True,
        )
        rec.log(
            f"{base}/avatars/up",
            rr.Arrows3D(
                origins=t.pos,
                vectors=2.0 * t.size * t.up,
                radii=0.15 * t.size,
                colors=rgba((0.1, 0.1, 0.1)),
            ),
            static=True,
        )
    if t.line is not None:
        width = task.spec.task.line.width if task.spec.task.line else 0.0015
        rec.log(
            f"{base}/line",
            rr.LineStrips3D([t.line], radii=0.5 * width, colors=rgba(LINE_RGBA)),
            static=True,
        )


def _spread(pos: np.ndarray) -> float:
    """Smallest distance between two of the points (inf for fewer than two)."""
    if len(pos) < 2:
        return float("inf")
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
    return float(d[np.triu_indices(len(pos), 1)].min())
