"""Task specs: pydantic models, the YAML loader with file:line errors, JSON Schema."""

import hashlib
import json
import os
from pathlib import Path

from ..bundled import find_spec, missing_spec_message
from .defaults import canonical_dump
from .hashes import task_hash, world_hash
from .loader import SpecError, SpecIssue, apply_overrides, load_model, read_yaml
from .models import Avatar, Cue, DomeScene, Line, Portal, Scope, Task, TaskSpec


def load_spec(path, overrides=()) -> TaskSpec:
    """Load and validate a task spec YAML file or bundled spec name; raises SpecError listing every problem."""
    found = find_spec(path)
    if not os.path.lexists(found):
        raise SpecError([SpecIssue(str(path), None, "", missing_spec_message())])
    return load_model(found, TaskSpec, list(overrides), context={"base": _folder(found)})


def _folder(path) -> Path:
    """The folder a spec's relative paths start from (its real location; a symlink loop is reported on reading)."""
    try:
        return Path(path).resolve().parent
    except (OSError, RuntimeError):
        return Path(path).absolute().parent


def spec_hash(spec: TaskSpec) -> str:
    """SHA-256 of the spec's canonical JSON, algorithm-dependent defaults as null (first 16 hex digits)."""
    text = json.dumps(canonical_dump(spec), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def json_schema() -> dict:
    """JSON Schema of a task spec, for editors."""
    return TaskSpec.model_json_schema()


__all__ = [
    "Avatar",
    "Cue",
    "DomeScene",
    "Line",
    "Portal",
    "Scope",
    "SpecError",
    "SpecIssue",
    "Task",
    "TaskSpec",
    "apply_overrides",
    "json_schema",
    "load_model",
    "load_spec",
    "read_yaml",
    "spec_hash",
    "task_hash",
    "world_hash",
]
