"""Avatars (the cue-coloured targets) and TraceLines' line, as visual geoms."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from ..spec import geometry as geo
from ..spec.anatomy import landmark_pose
from ..spec.models import Avatar, Cue, TaskSpec
from ..spec.reach import cue_for, portal_point

LINE_RGBA = (0.1, 0.25, 0.7, 1.0)
AVATAR_GROUP = 1


@dataclass(frozen=True)
class Targets:
    """Per-subtask target poses and cue tolerances, as arrays."""

    pos: np.ndarray  # (N, 3)
    fwd: np.ndarray  # (N, 3) facing direction
    up: np.ndarray  # (N, 3)
    quat: np.ndarray  # (N, 4) wxyz
    on_plate: np.ndarray  # (N,) bool
    at: np.ndarray  # (N, 2) spec coordinates: [x, y] m on the plate, [azimuth, elevation] deg on the dome
    heading: np.ndarray  # (N,) deg
    centring: np.ndarray  # (N,) rad
    horizon: np.ndarray  # (N,) rad
    dist: np.ndarray  # (N, 2) m
    dwell: np.ndarray  # (N,) s
    size: float  # avatar disk radius (m)
    line: np.ndarray | None  # (M, 3) dense line on the plate, or None

    def __len__(self) -> int:
        return len(self.pos)


def task_avatars(task_spec: TaskSpec) -> tuple[list[Avatar], np.ndarray | None]:
    """The avatars in order, and for TraceLines the dense line they are placed along."""
    task = task_spec.task
    if task.bodies:  # loose bodies: one subtask per body, its cue first on the body, then on the cup
        return [Avatar(surface="plate", at=b.at) for b in task.bodies], None
    if task.line is None:
        return list(task.avatars), None
    pts = np.asarray(task.line.points, float)
    dense = geo.catmull_rom(pts) if task.line.spline else pts
    way = geo.sample_polyline(dense, task.line.spacing)
    avatars = [Avatar(surface="plate", at=tuple(p), heading_deg=task.line.heading_deg) for p in way[1:]]
    return avatars, np.column_stack([dense, np.full(len(dense), 0.0003)])


def resolve_targets(task_spec: TaskSpec) -> Targets:
    """Target poses and tolerances of every subtask of the spec."""
    if task_spec.task.landmarks:
        return landmark_targets(task_spec)
    avatars, line = task_avatars(task_spec)
    r = task_spec.scene.radius
    poses = [geo.avatar_pose(r, a.surface, a.at, a.heading_deg) for a in avatars]
    cues: list[Cue] = [cue_for(task_spec, a) for a in avatars]
    pos, fwd, up = (np.array([p[k] for p in poses]) for k in range(3))
    quat = np.array([geo.mat_to_quat(geo.avatar_rotation(f, u)) for f, u in zip(fwd, up)])
    return Targets(
        pos=pos,
        fwd=fwd,
        up=up,
        quat=quat,
        on_plate=np.array([a.surface == "plate" for a in avatars]),
        at=np.array([a.at for a in avatars], float),
        heading=np.array([a.heading_deg for a in avatars], float),
        centring=np.radians([c.centring_deg for c in cues]),
        horizon=np.radians([c.horizon_deg for c in cues]),
        dist=np.array([c.distance for c in cues], float),
        dwell=np.array([c.dwell for c in cues], float),
        size=0.003 if line is not None else 0.006,
        line=line,
    )


def landmark_targets(task_spec: TaskSpec) -> Targets:
    """Targets of a tour: each landmark's organ point facing the portal, fixed (no jitter)."""
    marks = task_spec.task.landmarks
    portal = portal_point(task_spec)
    poses = [landmark_pose(task_spec.scene.anatomy[m.organ], portal) for m in marks]
    cues = [m.cue or task_spec.task.cue for m in marks]
    pos, fwd, up = (np.array([p[k] for p in poses]) for k in range(3))
    n = len(marks)
    return Targets(
        pos=pos,
        fwd=fwd,
        up=up,
        quat=np.array([geo.mat_to_quat(geo.avatar_rotation(f, u)) for f, u in zip(fwd, up)]),
        on_plate=np.zeros(n, bool),
        at=np.zeros((n, 2)),
        heading=np.zeros(n),
        centring=np.radians([c.centring_deg for c in cues]),
        horizon=np.radians([c.horizon_deg for c in cues]),
        dist=np.array([c.distance for c in cues], float),
        dwell=np.array([c.dwell for c in cues], float),
        size=0.004,
        line=None,
    )


def build_targets(spec: mujoco.MjSpec, targets: Targets, line_width: float = 0.0015) -> list[tuple[str, str]]:
    """Add a disk and an 'up' marker per avatar and the line's segments; return avatar geom names."""
    world = spec.worldbody
    names = []
    for i in range(len(targets)):
        rot = geo.avatar_rotation(targets.fwd[i], targets.up[i])
        q = geo.mat_to_quat(rot)
        s = targets.size
        disk, mark = f"avatar_{i}", f"avatar_{i}_up"
        world.add_geom(
            name=disk,
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            size=[s, 0.0004],
            pos=targets.pos[i],
            quat=q,
            rgba=(1, 0.6, 0.1, 1),
            group=AVATAR_GROUP,
            contype=0,
            conaffinity=0,
        )
        world.add_geom(
            name=mark,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[0.2 * s, 0.45 * s, 0.0005],
            pos=targets.pos[i] + 0.9 * s * targets.up[i] + 0.0002 * targets.fwd[i],
            quat=q,
            rgba=(0.1, 0.1, 0.1, 1),
            group=AVATAR_GROUP,
            contype=0,
            conaffinity=0,
        )
        names.append((disk, mark))
    if targets.line is not None:
        for k, (a, b) in enumerate(zip(targets.line[:-1], targets.line[1:])):
            if np.linalg.norm(b - a) < 1e-6:
                continue
            world.add_geom(
                name=f"line_{k}",
                type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                fromto=[*a, *b],
                size=[0.5 * line_width, 0, 0],
                rgba=LINE_RGBA,
                group=AVATAR_GROUP,
                contype=0,
                conaffinity=0,
            )
    return names
