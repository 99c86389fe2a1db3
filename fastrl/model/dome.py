"""The FAST dome scene: a tiled hemispherical shell with portals over a base plate."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..spec import geometry as geo
from ..spec.models import DomeScene

SHELL_RGBA = (0.93, 0.86, 0.78, 1.0)
PLATE_RGBA = (0.85, 0.85, 0.88, 1.0)
PORTAL_RGBA = (0.15, 0.15, 0.18, 1.0)
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 2  # collides with the scope tip only
SHELL_GROUP = 2  # hidden in the outside view


def build_dome(spec: mujoco.MjSpec, scene: DomeScene) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Add plate, shell tiles and portal rims to the world; return {portal: (point, rotation)}."""
    add_floor(spec, "plate", scene.radius, PLATE_RGBA)
    return add_shell(spec, scene, SHELL_RGBA, PORTAL_RGBA)


def add_floor(spec: mujoco.MjSpec, name: str, radius: float, rgba) -> None:
    """The flat disk the shell stands on (the dome's plate, the abdomen's posterior wall), its top at z = 0."""
    spec.worldbody.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[radius + 0.03, 0.005],
        pos=[0, 0, -0.005],
        rgba=rgba,
        contype=WORLD_CONTYPE,
        conaffinity=WORLD_CONAFFINITY,
    )


def add_shell(spec: mujoco.MjSpec, scene, shell_rgba, portal_rgba) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """A hemispherical shell of tiles with holes at the scene's portals, and a rim per portal."""
    world = spec.worldbody
    r, t = scene.radius, scene.thickness
    portals = {p.name: geo.portal_frame(r, p.azimuth, p.elevation, p.aim) for p in scene.portals}
    holes = [(geo.sphere_point(1.0, p.azimuth, p.elevation), p.radius / r) for p in scene.portals]
    d_el = math.radians(90.0 / (scene.rings + 0.5))
    d_az = 2 * math.pi / scene.sectors
    for k in range(scene.rings):
        el0, el1 = k * d_el, (k + 1) * d_el
        el = 0.5 * (el0 + el1)
        for j in range(scene.sectors):
            az = (j + 0.5) * d_az
            normal = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
            if any(
                math.acos(np.clip(normal @ h, -1, 1)) < 0.6 * max(d_el, d_az * math.cos(el)) + hr for h, hr in holes
            ):
                continue
            e_az = np.array([-math.sin(az), math.cos(az), 0.0])
            rot = np.column_stack([e_az, np.cross(normal, e_az), normal])
            half = [0.53 * (r + t) * d_az * math.cos(el0), 0.53 * (r + t) * d_el, 0.5 * t]
            world.add_geom(
                name=f"shell_{k}_{j}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=half,
                pos=(r + 0.5 * t) * normal,
                quat=geo.mat_to_quat(rot),
                rgba=shell_rgba,
                group=SHELL_GROUP,
                contype=WORLD_CONTYPE,
                conaffinity=WORLD_CONAFFINITY,
            )
    el_cap = scene.rings * d_el
    world.add_geom(
        name="shell_crown",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[(r + t) * math.cos(el_cap) * 1.05, 0.5 * t],
        pos=[0, 0, r * math.sin(el_cap) + 0.5 * t + r * (1 - math.sin(el_cap)) * 0.5],
        rgba=shell_rgba,
        group=SHELL_GROUP,
        contype=WORLD_CONTYPE,
        conaffinity=WORLD_CONAFFINITY,
    )
    for name, (point, _) in portals.items():
        normal = point / np.linalg.norm(point)
        world.add_geom(
            name=f"portal_{name}",
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[1.4 * next(p.radius for p in scene.portals if p.name == name), 0.3 * t],
            pos=point + (t + 0.3 * t) * normal,
            quat=geo.mat_to_quat(geo.frame_from_z(normal)),
            rgba=portal_rgba,
            group=SHELL_GROUP,
            contype=0,
            conaffinity=0,
        )
    return portals
