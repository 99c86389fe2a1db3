"""The task's identity for recordings: what a trajectory's replay and the endoscope's picture depend on, hashed."""

from __future__ import annotations

import hashlib
import json

from .defaults import drop_unused_extensions

SCOPE_NOISE = ("pitch_deg", "yaw_deg", "insertion", "roll_deg", "cable_deg")
DEFAULT_TERMINATIONS = {"subtasks_done": {}}


def _sha(data: dict) -> str:
    """First 16 hex digits of the SHA-256 of the data's canonical JSON."""
    return hashlib.sha256(json.dumps(data, sort_keys=True, separators=(",", ":")).encode()).hexdigest()[:16]


def as_recorded(world: dict, resets: dict) -> dict:
    """A dumped world with the reset terms written where recordings were hashed with them (before spec 0.3.0).

    Trajectories carry the task hash they were recorded in, and scoring refuses another: declaring the start
    noise and the jitter as terms must not turn every recording into another task's."""
    noise = resets.get("scope_noise", {})
    world["scope"]["start"]["noise"] = [float(noise.get(k, 0.0)) for k in SCOPE_NOISE]
    noise = resets.get("instrument_noise", {})
    for instrument in world.get("instruments", []):
        instrument["start"]["noise"] = [float(noise.get(k, 0.0)) for k in SCOPE_NOISE[:4]]
    jitter = resets.get("avatar_jitter", {})
    world["task"]["jitter"] = [float(jitter.get("plate", 0.0)), float(jitter.get("dome", 0.0))]
    return world


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
