"""LooseBodies in the model: free spheres on the plate, the cup, and a weld per body for the grasper to hold it by."""

from __future__ import annotations

import math

import mujoco

BODY_RGBA = (0.95, 0.95, 0.3, 1.0)
CUP_RGBA, CUP_MARK_RGBA = (0.35, 0.35, 0.4, 1.0), (0.2, 0.7, 0.3, 1.0)
BODY_CONTYPE, BODY_CONAFFINITY = 2, 1  # rests on dome, plate and cup; the scope tip passes through it
WORLD_CONTYPE, WORLD_CONAFFINITY = 1, 2
CUP_WALLS, CUP_WALL = 12, 0.0015  # wall boxes around, their half-thickness (m)


def build_loose(spec: mujoco.MjSpec, task_spec) -> None:
    """Add the cup (walls and a marked floor) and one free sphere per body, welded to the grasper only when held."""
    task = task_spec.task
    grasper = next(i for i in task_spec.instruments if i.kind == "grasper")
    cup, world = task.cup, spec.worldbody
    world.add_geom(
        name="cup_mark",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[cup.radius, 0.0004],
        pos=[*cup.at, 0.0004],
        rgba=CUP_MARK_RGBA,
        contype=0,
        conaffinity=0,
    )
    half = cup.radius * math.tan(math.pi / CUP_WALLS) + CUP_WALL
    for k in range(CUP_WALLS):
        a = 2 * math.pi * k / CUP_WALLS
        world.add_geom(
            name=f"cup_wall_{k}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[CUP_WALL, half, 0.5 * cup.height],
            pos=[
                cup.at[0] + (cup.radius + CUP_WALL) * math.cos(a),
                cup.at[1] + (cup.radius + CUP_WALL) * math.sin(a),
                0.5 * cup.height,
            ],
            euler=[0, 0, a],
            rgba=CUP_RGBA,
            contype=WORLD_CONTYPE,
            conaffinity=WORLD_CONAFFINITY,
        )
    for i, b in enumerate(task.bodies):
        body = world.add_body(name=f"loose_{i}", pos=[*b.at, b.radius + 1e-4])
        body.add_freejoint(name=f"loose_{i}")
        body.add_geom(
            name=f"loose_{i}",
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            size=[b.radius],
            rgba=BODY_RGBA,
            mass=0.002,
            contype=BODY_CONTYPE,
            conaffinity=BODY_CONAFFINITY,
            condim=4,
            friction=[1.0, 0.01, 0.001],
        )
        spec.add_exclude(bodyname1=f"{grasper.name}_shaft", bodyname2=f"loose_{i}")
        spec.add_equality(
            name=f"hold_{i}",
            type=mujoco.mjtEq.mjEQ_WELD,
            name1=f"{grasper.name}_shaft",
            name2=f"loose_{i}",
            objtype=mujoco.mjtObj.mjOBJ_BODY,
            active=False,
        )
