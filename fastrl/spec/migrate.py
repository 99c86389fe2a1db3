"""Specs written before today's layout (run folders, trajectories that carry their spec, Minari datasets), upgraded."""

from __future__ import annotations

import copy
from typing import Any

from .base import _fail

PORTAL_NOISE = ("pitch_deg", "yaw_deg", "insertion", "roll_deg", "cable_deg")
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
    scope_start = (data.get("scope") or {}).get("start")
    noise = scope_start.pop("noise", None) if isinstance(scope_start, dict) else None
    resets["scope_noise"] = dict(zip(PORTAL_NOISE, noise if isinstance(noise, list | tuple) else [0.0] * 5))
    instruments = [i for i in data.get("instruments") or [] if isinstance(i, dict)]
    noises = [tuple((i.get("start") or {}).pop("noise", (0.0,) * 4)) for i in instruments]
    if noises:
        if len(set(noises)) > 1:
            _fail("instruments.1.start.noise", "0.3 has one instrument_noise for every instrument: give them one noise")
        resets["instrument_noise"] = dict(zip(PORTAL_NOISE, noises[0]))
    jitter = (data.get("task") or {}).pop("jitter", None)
    if isinstance(jitter, list | tuple) and any(jitter):
        resets["avatar_jitter"] = dict(zip(("plate", "dome"), jitter))
    episode = data.setdefault("episode", {})
    if isinstance(episode, dict):
        episode.setdefault("resets", resets)
    return data


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
