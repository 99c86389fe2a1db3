"""The arthroscope: an exact fulcrum chain rooted at the portal point."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..spec import geometry as geo
from ..spec.models import Scope

JOINTS = ("pitch", "yaw", "insertion", "roll", "cable")
TIP_CONTYPE, TIP_CONAFFINITY = 2, 1
SHAFT_RGBA = (0.55, 0.57, 0.6, 1.0)
HINGE, SLIDE = mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE


def joint_ranges(scope: Scope) -> np.ndarray:
    """(5, 2) lower and upper limits of the portal coordinates (rad, rad, m, rad, rad)."""
    p = math.radians(scope.pivot_limit_deg)
    return np.array([[-p, p], [-p, p], list(scope.insertion), [-math.pi, math.pi], [-math.pi, math.pi]])


LENS_CAMERA = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])  # looks along the lens +z, up +y


def build_scope(spec: mujoco.MjSpec, scope: Scope, point: np.ndarray, rot: np.ndarray) -> None:
    """Add the pivot, shaft and optics bodies, their joints, servos, tip light and camera."""
    ranges = joint_ranges(scope)
    radius = 0.5 * scope.diameter
    pivot = spec.worldbody.add_body(name="scope_pivot", pos=point, quat=geo.mat_to_quat(rot), gravcomp=1)
    for name, axis, rng in (("pitch", [1, 0, 0], ranges[0]), ("yaw", [0, 1, 0], ranges[1])):
        pivot.add_joint(
            name=name,
            type=HINGE,
            axis=axis,
            range=rng,
            limited=mujoco.mjtLimited.mjLIMITED_TRUE,
            damping=scope.damping,
            frictionloss=scope.frictionloss,
            armature=2e-3,
        )
    pivot.add_geom(
        name="pivot_mass",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[radius],
        mass=1e-3,
        contype=0,
        conaffinity=0,
        group=3,
    )
    shaft = pivot.add_body(name="scope_shaft", gravcomp=1)
    shaft.add_joint(
        name="insertion",
        type=SLIDE,
        axis=[0, 0, 1],
        range=ranges[2],
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        damping=10 * scope.damping,
        frictionloss=10 * scope.frictionloss,
        armature=2e-2,
    )
    shaft.add_joint(
        name="roll",
        type=HINGE,
        axis=[0, 0, 1],
        range=ranges[3],
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        damping=0.1 * scope.damping,
        armature=1e-3,
    )
    add_shaft_geoms(shaft, "", scope.shaft_length, radius, SHAFT_RGBA, (TIP_CONTYPE, TIP_CONAFFINITY))
    optics = shaft.add_body(name="scope_optics")
    optics.add_joint(
        name="cable",
        type=HINGE,
        axis=[0, 0, 1],
        range=ranges[4],
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        damping=0.1 * scope.damping,
        armature=1e-3,
    )
    optics.add_geom(
        name="light_post",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.002, 0.006, 0.002],
        pos=[0, 0.008, -scope.shaft_length + 0.01],
        rgba=(0.2, 0.2, 0.2, 1),
        mass=1e-3,
        contype=0,
        conaffinity=0,
    )
    # The lens looks along the shaft tilted by the optics angle; turning the light cable sweeps it round a
    # cone while the image stays upright with the camera head: the lens counter-rotates about its own axis.
    th = math.radians(scope.optics_deg)
    lens = optics.add_body(name="scope_lens", quat=[math.cos(th / 2), math.sin(th / 2), 0, 0])
    lens.add_joint(name="lens", type=HINGE, axis=[0, 0, 1], range=[-2 * math.pi, 2 * math.pi], armature=1e-3)
    lens.add_geom(
        name="lens_mass",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[0.5 * radius],
        mass=1e-4,
        contype=0,
        conaffinity=0,
        group=3,
    )
    spec.add_equality(
        name="lens_counter", type=mujoco.mjtEq.mjEQ_JOINT, name1="lens", name2="cable", data=[0, -1, 0, 0, 0] + [0] * 7
    )
    lens.add_camera(name="endoscope", pos=[0, 0, 0], quat=geo.mat_to_quat(LENS_CAMERA), fovy=scope.fov_deg)
    lens.add_light(
        name="scope_light",
        pos=[0, 0, 0],
        dir=[0, 0, 1],
        castshadow=False,
        diffuse=[0.9, 0.9, 0.85],
        attenuation=[0.3, 8.0, 0.0],
        cutoff=0.6 * scope.fov_deg + 10,
        exponent=2,
    )
    gains = {
        "pitch": (3.0, 0.12),
        "yaw": (3.0, 0.12),
        "insertion": (80.0, 2.5),
        "roll": (0.6, 0.04),
        "cable": (0.6, 0.04),
    }
    for name, rng in zip(JOINTS, ranges):
        act = spec.add_actuator(
            name=f"servo_{name}",
            target=name,
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
            ctrlrange=rng,
            ctrllimited=mujoco.mjtLimited.mjLIMITED_TRUE,
        )
        act.set_to_position(kp=gains[name][0], kv=gains[name][1])


def add_shaft_geoms(
    body: mujoco.MjsBody, prefix: str, length: float, radius: float, rgba, tip_collision: tuple[int, int]
) -> None:
    """A shaft (visual only) ending at the body's origin in a tip sphere that collides (contype, conaffinity)."""
    body.add_geom(
        name=f"{prefix}shaft",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        fromto=[0, 0, -length, 0, 0, -radius],
        size=[radius, 0, 0],
        rgba=rgba,
        mass=0.02,
        contype=0,
        conaffinity=0,
    )
    body.add_geom(
        name=f"{prefix}tip",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[radius],
        rgba=rgba,
        mass=1e-3,
        contype=tip_collision[0],
        conaffinity=tip_collision[1],
        condim=3,
    )
