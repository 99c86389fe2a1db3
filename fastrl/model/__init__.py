"""Compile task specs into MuJoCo models: scenes, the arthroscope, avatars and lines."""

from .compiler import SCENES, CompiledTask, build_mjspec, compile_task, register_scene
from .loaded import load_task
from .scope import JOINTS, joint_ranges
from .targets import Targets, resolve_targets

__all__ = [
    "JOINTS",
    "SCENES",
    "CompiledTask",
    "Targets",
    "build_mjspec",
    "compile_task",
    "joint_ranges",
    "load_task",
    "register_scene",
    "resolve_targets",
]
