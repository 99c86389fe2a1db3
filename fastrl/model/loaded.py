"""A spec file (or bundled spec's name) with overrides, validated and compiled in one step."""

from __future__ import annotations

from ..spec import SpecError, SpecIssue, load_spec
from .compiler import CompiledTask, compile_task


def load_task(path, overrides=()) -> CompiledTask:
    """Validate and compile a spec; every problem (MuJoCo compile errors too) raises SpecError."""
    spec = load_spec(path, overrides or ())
    try:
        return compile_task(spec)
    except ValueError as e:  # mujoco reports compile errors as ValueError
        detail = " ".join(str(e).split())
        raise SpecError([SpecIssue(str(path), None, "", f"MuJoCo cannot compile the model: {detail}")]) from None
