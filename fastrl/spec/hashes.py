"""The task's identity for recordings: what a trajectory's replay and the endoscope's picture depend on, hashed."""

from __future__ import annotations

import hashlib
import json

from .defaults import drop_unused_extensions
from .episode import DEFAULT_TERMINATIONS
from .migrate import as_recorded


def _sha(data: dict) -> str:
    """First 16 hex digits of the SHA-256 of the data's canonical JSON."""
    return hashlib.sha256(json.dumps(data, sort_keys=True, separators=(",", ":")).encode()).hexdigest()[:16]


def task_hash(spec) -> str:
    """SHA-256 of what a trajectory's replay depends on: scene, scope, task, episode and its terms (16 hex digits)."""
    world = spec.model_dump(mode="json", include={"scene", "scope", "task", "episode", "instruments"})
    episode = world["episode"]
    resets, terminations = episode.pop("resets"), episode.pop("terminations")
    if terminations != DEFAULT_TERMINATIONS:
        episode["terminations"] = terminations
    return _sha(drop_unused_extensions(as_recorded(world, resets)))


def world_hash(spec) -> str:
    """SHA-256 of what the endoscope shows: the task's world without its cue's tolerances (16 hex digits)."""
    world = as_recorded(
        spec.model_dump(mode="json", include={"scene", "scope", "task", "instruments"}), spec.episode.resets
    )
    world["task"].pop("cue", None)
    return _sha(world)
