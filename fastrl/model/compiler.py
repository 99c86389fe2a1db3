"""TaskSpec -> mujoco.MjSpec -> MjModel, with named handles into the compiled model."""

from __future__ import annotations

import copy
import dataclasses
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np

from ..spec.models import TaskSpec
from .abdomen import build_abdomen
from .dome import build_dome
from .instruments import InstrumentHandles, build_instrument, instrument_handles
from .loose import build_loose
from .scope import JOINTS, build_scope, joint_ranges
from .targets import Targets, build_targets, resolve_targets

SceneBuilder = Callable[[mujoco.MjSpec, object], dict]
SCENES: dict[str, SceneBuilder] = {"fast_dome": build_dome, "abdomen": build_abdomen}
_COMPILED: OrderedDict[str, CompiledTask] = OrderedDict()  # the last tasks compiled, by their spec's JSON
_KEEP = 8


def register_scene(kind: str, builder: SceneBuilder) -> None:
    """Add a scene kind: builder(mjspec, scene) adds geoms and returns {portal: (point, rotation)}."""
    SCENES[kind] = builder
    _COMPILED.clear()


@dataclass
class CompiledTask:
    """A compiled model with the indices the environment needs."""

    spec: TaskSpec
    model: mujoco.MjModel
    targets: Targets
    portal_point: np.ndarray
    portal_rot: np.ndarray
    ranges: np.ndarray  # (5, 2) portal-coordinate limits
    qadr: np.ndarray  # qpos addresses of the 5 portal joints
    vadr: np.ndarray  # dof addresses
    lens_qadr: int  # qpos address of the lens counter-rotation (= -cable)
    camera: int
    tip_geom: int
    avatar_geoms: np.ndarray  # (N, 2) disk and up-marker geom ids
    xml: str
    instruments: list[InstrumentHandles] = field(default_factory=list)  # probes and graspers, in spec order


def build_mjspec(task_spec: TaskSpec) -> tuple[mujoco.MjSpec, dict]:
    """Build the MjSpec of a task; also return the scene's portal frames."""
    spec = mujoco.MjSpec()
    spec.modelname = task_spec.name
    spec.compiler.degree = False
    ep = task_spec.episode
    spec.option.timestep = 1.0 / (ep.control_hz * ep.substeps)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.visual.quality.shadowsize = 0
    spec.visual.quality.offsamples = 0
    spec.visual.quality.numslices = 16  # coarser tessellation of round geoms: faster software rendering
    spec.visual.quality.numstacks = 6
    spec.visual.global_.offwidth = 640
    spec.visual.global_.offheight = 480
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    spec.visual.headlight.diffuse = [0.4, 0.4, 0.4]
    spec.stat.center = [0, 0, 0.04]
    spec.stat.extent = 0.3
    portals = SCENES[task_spec.scene.kind](spec, task_spec.scene)
    point, rot = portals[task_spec.scope.portal]
    build_scope(spec, task_spec.scope, point, rot)
    for inst in task_spec.instruments:
        build_instrument(spec, inst, *portals[inst.portal])
    targets = resolve_targets(task_spec)
    build_targets(spec, targets, task_spec.task.line.width if task_spec.task.line else 0.0015)
    if task_spec.task.bodies:
        build_loose(spec, task_spec)
    return spec, portals


def compile_task(task_spec: TaskSpec) -> CompiledTask:
    """A compiled task with a MuJoCo model of its own (a spec compiled before is copied, not built again)."""
    key = task_spec.model_dump_json()
    base = _COMPILED.get(key)
    if base is None:
        base = _COMPILED[key] = build_task(task_spec)
        while len(_COMPILED) > _KEEP:
            _COMPILED.popitem(last=False)
    return dataclasses.replace(base, model=copy.copy(base.model))


def build_task(task_spec: TaskSpec) -> CompiledTask:
    """Compile a task spec into a MuJoCo model and its handles."""
    spec, portals = build_mjspec(task_spec)
    model = spec.compile()
    point, rot = portals[task_spec.scope.portal]
    targets = resolve_targets(task_spec)
    jid = [model.joint(n).id for n in JOINTS]
    return CompiledTask(
        spec=task_spec,
        model=model,
        targets=targets,
        portal_point=point,
        portal_rot=rot,
        ranges=joint_ranges(task_spec.scope),
        qadr=np.array([model.jnt_qposadr[j] for j in jid]),
        vadr=np.array([model.jnt_dofadr[j] for j in jid]),
        lens_qadr=int(model.jnt_qposadr[model.joint("lens").id]),
        camera=model.camera("endoscope").id,
        tip_geom=model.geom("tip").id,
        avatar_geoms=np.array(
            [[model.geom(f"avatar_{i}").id, model.geom(f"avatar_{i}_up").id] for i in range(len(targets))]
        ),
        xml=spec.to_xml(),
        instruments=[instrument_handles(model, inst, *portals[inst.portal]) for inst in task_spec.instruments],
    )
