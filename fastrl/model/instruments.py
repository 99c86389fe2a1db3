"""Probes and graspers: the scope's exact fulcrum chain (pitch, yaw, insertion, roll; grasper jaw) at their portals."""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from ..spec import geometry as geo
from ..spec.instruments import Instrument
from .scope import add_shaft_geoms

TOOL_CONTYPE, TOOL_CONAFFINITY = 2, 3  # collides with the dome, the plate, the scope tip and other tips
TOOL_RGBA = (0.75, 0.72, 0.45, 1.0)
HINGE, SLIDE = mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE
GAINS = {"pitch": (3.0, 0.12), "yaw": (3.0, 0.12), "insertion": (80.0, 2.5), "roll": (0.6, 0.04), "jaw": (0.3, 0.02)}


@dataclass
class InstrumentHandles:
    """Indices of one compiled instrument."""

    spec: Instrument
    point: np.ndarray  # portal point
    rot: np.ndarray  # portal rotation
    ranges: np.ndarray  # (k, 2) coordinate limits
    qadr: np.ndarray  # (k,) qpos addresses
    ctrl: np.ndarray  # (k,) actuator indices
    tip_geom: int
    tip_body: int

    @property
    def joints(self) -> tuple[str, ...]:
        """Coordinate names."""
        return instrument_joints(self.spec)


def instrument_joints(inst: Instrument) -> tuple[str, ...]:
    """Its portal coordinates: pitch, yaw, insertion, roll, and the grasper's jaw."""
    return ("pitch", "yaw", "insertion", "roll", "jaw")[: inst.coordinates]


def instrument_ranges(inst: Instrument) -> np.ndarray:
    """(k, 2) limits of its portal coordinates (rad, rad, m, rad[, rad])."""
    p = math.radians(inst.pivot_limit_deg)
    rows = [[-p, p], [-p, p], list(inst.insertion), [-math.pi, math.pi], [0.0, math.radians(inst.jaw_deg)]]
    return np.array(rows[: inst.coordinates])


def _joint(body, name, kind, axis, rng, inst: Instrument, scale: float, armature: float):
    """A limited joint with the portal's entry friction scaled."""
    body.add_joint(
        name=name,
        type=kind,
        axis=axis,
        range=rng,
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        damping=scale * inst.damping,
        frictionloss=scale * inst.frictionloss if kind == SLIDE or name.endswith(("pitch", "yaw")) else 0.0,
        armature=armature,
    )


def build_instrument(spec: mujoco.MjSpec, inst: Instrument, point: np.ndarray, rot: np.ndarray) -> None:
    """Add the pivot, shaft, tip (colliding) and jaws of an instrument, its joints and position servos."""
    n, ranges, radius = inst.name, instrument_ranges(inst), 0.5 * inst.diameter
    pivot = spec.worldbody.add_body(name=f"{n}_pivot", pos=point, quat=geo.mat_to_quat(rot), gravcomp=1)
    _joint(pivot, f"{n}_pitch", HINGE, [1, 0, 0], ranges[0], inst, 1.0, 2e-3)
    _joint(pivot, f"{n}_yaw", HINGE, [0, 1, 0], ranges[1], inst, 1.0, 2e-3)
    pivot.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius], mass=1e-3, contype=0, conaffinity=0, group=3)
    shaft = pivot.add_body(name=f"{n}_shaft", gravcomp=1)
    _joint(shaft, f"{n}_insertion", SLIDE, [0, 0, 1], ranges[2], inst, 10.0, 2e-2)
    _joint(shaft, f"{n}_roll", HINGE, [0, 0, 1], ranges[3], inst, 0.1, 1e-3)
    add_shaft_geoms(shaft, f"{n}_", inst.shaft_length, radius, TOOL_RGBA, (TOOL_CONTYPE, TOOL_CONAFFINITY))
    if inst.kind == "probe":  # the palpation hook: a short bent end, visual only
        shaft.add_geom(
            name=f"{n}_hook",
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            fromto=[0, 0, 0, 0, 0.004, 0.002],
            size=[0.6 * radius, 0, 0],
            rgba=TOOL_RGBA,
            mass=1e-4,
            contype=0,
            conaffinity=0,
        )
    else:
        jaw = shaft.add_body(name=f"{n}_jaw")
        _joint(jaw, f"{n}_jaw", HINGE, [1, 0, 0], ranges[4], inst, 0.1, 1e-3)
        for side in (1, -1):
            jaw.add_geom(
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[0.0012, 0.0004, 0.004],
                pos=[0, side * 0.0012, 0.003],
                rgba=TOOL_RGBA,
                mass=1e-4,
                contype=0,
                conaffinity=0,
            )
    for name, rng in zip(instrument_joints(inst), ranges):
        act = spec.add_actuator(
            name=f"servo_{n}_{name}",
            target=f"{n}_{name}",
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
            ctrlrange=rng,
            ctrllimited=mujoco.mjtLimited.mjLIMITED_TRUE,
        )
        act.set_to_position(kp=GAINS[name][0], kv=GAINS[name][1])


def instrument_handles(
    model: mujoco.MjModel, inst: Instrument, point: np.ndarray, rot: np.ndarray
) -> InstrumentHandles:
    """The compiled instrument's indices."""
    names = [f"{inst.name}_{j}" for j in instrument_joints(inst)]
    return InstrumentHandles(
        spec=inst,
        point=point,
        rot=rot,
        ranges=instrument_ranges(inst),
        qadr=np.array([model.jnt_qposadr[model.joint(j).id] for j in names]),
        ctrl=np.array([model.actuator(f"servo_{j}").id for j in names]),
        tip_geom=model.geom(f"{inst.name}_tip").id,
        tip_body=model.body(f"{inst.name}_shaft").id,
    )


def aim(point: np.ndarray, rot: np.ndarray, target: np.ndarray, back: float) -> np.ndarray:
    """Pitch, yaw and insertion that put the tip on the line to `target`, `back` metres short of it."""
    d = (np.asarray(target, float) - point) @ rot
    dist = float(np.linalg.norm(d))
    axis = d / dist
    return np.array([math.atan2(-axis[1], axis[2]), math.asin(float(np.clip(axis[0], -1, 1))), dist - back])
