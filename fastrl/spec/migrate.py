"""Specs of the 0.2 layout (run folders, trajectories that carry their spec, datasets) upgraded, and written back."""

from __future__ import annotations

import copy
from typing import Any

from ..terms.episode import PORTAL_NOISE as NOISE_DOMAINS
from .base import _fail

PORTAL_NOISE = tuple(NOISE_DOMAINS)  # 0.2's noise lists, in this order
OLD_LAYOUT = (
    "written in the 0.2 layout and read as 0.3: the start noise and task.jitter are now episode.resets "
    "(scope_noise, instrument_noise, avatar_jitter), experiment is now study"
)


def upgraded(data: Any) -> Any:
    """Spec data in the 0.2 layout in 0.3's: start noise and jitter in episode.resets, `experiment` named `study`.

    0.2 drew the scope's and every instrument's noise at each start even where it was zero, so the upgrade declares
    both (zeros included) and the random draws stay in the same order; the jitter drew nothing at zero."""
    if not in_old_layout(data):
        return data
    data = copy.deepcopy(data)
    if "experiment" in data and "study" not in data:
        data["study"] = data.pop("experiment")
    if not _old(data):
        return data
    resets = {}
    scope = data.get("scope")
    scope_start = scope.get("start") if isinstance(scope, dict) else None
    if isinstance(scope_start, dict) and _numbers(scope_start.get("noise"), 5):
        resets["scope_noise"] = dict(zip(PORTAL_NOISE, scope_start.pop("noise")))
    elif not isinstance(scope_start, dict) or "noise" not in scope_start:
        resets["scope_noise"] = dict.fromkeys(PORTAL_NOISE, 0.0)  # 0.2's default, drawn all the same
    noises = []
    for instrument in data.get("instruments") if isinstance(data.get("instruments"), list) else []:
        start = instrument.get("start") if isinstance(instrument, dict) else None
        if isinstance(start, dict) and _numbers(start.get("noise"), 4):
            noises.append(tuple(start.pop("noise")))
        elif not isinstance(start, dict) or "noise" not in start:
            noises.append((0.0,) * 4)  # 0.2's default, drawn all the same
    if noises:
        if len(set(noises)) > 1:
            _fail("instruments.1.start.noise", "0.3 has one instrument_noise for every instrument: give them one noise")
        resets["instrument_noise"] = dict(zip(PORTAL_NOISE, noises[0]))
    task = data.get("task")
    if isinstance(task, dict) and _numbers(task.get("jitter"), 2):
        jitter = task.pop("jitter")
        if any(jitter):
            resets["avatar_jitter"] = dict(zip(("plate", "dome"), jitter))
    episode = data.setdefault("episode", {})
    if isinstance(episode, dict):
        episode.setdefault("resets", resets)
    return data


def as_recorded(world: dict, resets: dict) -> dict:
    """A dumped world with the reset terms written where recordings were hashed with them (before spec 0.3.0).

    Trajectories carry the task hash they were recorded in, and scoring refuses another: declaring the start
    noise and the jitter as terms must not turn every recording into another task's."""
    noise = resets.get("scope_noise", {})
    world["scope"]["start"]["noise"] = [float(noise.get(k, 0.0)) for k in PORTAL_NOISE]
    noise = resets.get("instrument_noise", {})
    for instrument in world.get("instruments", []):
        instrument["start"]["noise"] = [float(noise.get(k, 0.0)) for k in PORTAL_NOISE[:4]]
    jitter = resets.get("avatar_jitter", {})
    world["task"]["jitter"] = [float(jitter.get("plate", 0.0)), float(jitter.get("dome", 0.0))]
    return world


def in_old_layout(data: Any) -> bool:
    """Whether spec data is written in the 0.2 layout (what `upgraded` changes)."""
    return isinstance(data, dict) and (_old(data) or "experiment" in data)


def _old(data: dict) -> bool:
    """Whether spec data holds a field of the 0.2 layout."""
    start = (data.get("scope") or {}).get("start") if isinstance(data.get("scope"), dict) else None
    instruments = data.get("instruments") if isinstance(data.get("instruments"), list) else []
    return (
        (isinstance(start, dict) and "noise" in start)
        or any(isinstance(i, dict) and isinstance(i.get("start"), dict) and "noise" in i["start"] for i in instruments)
        or (isinstance(data.get("task"), dict) and "jitter" in data["task"])
    )


def _numbers(value: Any, n: int) -> bool:
    """Whether a 0.2 field holds the n numbers it held then (anything else is left for the spec's checks to name)."""
    return (
        isinstance(value, list | tuple)
        and len(value) == n
        and all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)
    )
