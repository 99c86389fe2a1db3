"""Checks of untrusted trajectory content: array types and sizes, metadata types, portal-coordinate ranges."""

from __future__ import annotations

import json
import math
import zipfile
import zlib
from numbers import Integral, Real
from typing import BinaryIO

import numpy as np

from ..spec.limits import (
    MAX_META_CHARS,
    MAX_META_DEPTH,
    MAX_SECONDS,
    MAX_SEED,
    MAX_TRAJECTORY_BYTES,
    MAX_TRAJECTORY_SAMPLES,
    MIN_TIME_STEP,
    RANGE_TOLERANCE,
)

COORDINATES = ("pitch", "yaw", "insertion", "roll", "cable")  # rad, rad, m, rad, rad
UNITS = ("rad", "rad", "m", "rad", "rad")
ARRAYS = ("time", "portal", "actions", "meta", "instruments", "bodies", "frames")  # the arrays a trajectory reads


def real_array(value, name: str) -> np.ndarray:
    """The value as a float array; ValueError unless it holds real numbers (not complex, text or objects)."""
    a = np.asarray(value)
    if a.dtype.kind not in "iuf":
        raise ValueError(f"{name} must hold real numbers, got dtype {a.dtype}")
    if a.shape and a.shape[0] > MAX_TRAJECTORY_SAMPLES:
        raise ValueError(f"{name} has {a.shape[0]:,} rows, at most {MAX_TRAJECTORY_SAMPLES:,} are allowed")
    return a.astype(float, copy=False)


def frames_array(value) -> np.ndarray:
    """Video frames as a uint8 array; ValueError unless they are uint8 with at most MAX_TRAJECTORY_SAMPLES rows."""
    a = np.asarray(value)
    if a.dtype != np.uint8:
        raise ValueError(f"frames must be uint8 (0-255 RGB), got dtype {a.dtype}")
    if a.shape and a.shape[0] > MAX_TRAJECTORY_SAMPLES:
        raise ValueError(f"frames has {a.shape[0]:,} rows, at most {MAX_TRAJECTORY_SAMPLES:,} are allowed")
    return a


def time_problem(time: np.ndarray) -> str | None:
    """Why increasing sample times are not plausible seconds (a span over a day, steps under a microsecond)."""
    span, step = float(time[-1] - time[0]), np.diff(time)
    if not span <= MAX_SECONDS:
        return f"time spans {span:.3g} s, more than a day ({MAX_SECONDS:,} s): is it in seconds?"
    if step.min() < MIN_TIME_STEP:
        i = int(np.flatnonzero(step < MIN_TIME_STEP)[0])
        return f"samples {i} and {i + 1} are {step[i]:.3g} s apart, less than {MIN_TIME_STEP:g} s: is time in seconds?"
    return None


def _whole(value, low: int, high: int) -> bool:
    return isinstance(value, Integral) and not isinstance(value, bool) and low <= value <= high


def meta_problem(meta) -> str | None:
    """Why trajectory metadata has the wrong shape or types (seed, skill, subject, names), or None."""
    if not isinstance(meta, dict):
        return f"meta must be a JSON object, got {type(meta).__name__}"
    if "seed" in meta and not _whole(meta["seed"], 0, MAX_SEED):
        return f"meta.seed must be a whole number from 0 to 2^63 - 1, got {_shown(meta['seed'])}"
    skill = meta.get("skill")
    if skill is not None and not (
        isinstance(skill, str) or (isinstance(skill, Real) and not isinstance(skill, bool) and math.isfinite(skill))
    ):
        return f"meta.skill must be a number or a text label, got {_shown(skill)}"
    subject = meta.get("subject")
    if subject is not None and not (isinstance(subject, str) or _whole(subject, -MAX_SEED, MAX_SEED)):
        return f"meta.subject must be a text or a whole number, got {_shown(subject)}"
    for key in ("spec", "spec_hash", "task_hash", "source"):
        if meta.get(key) is not None and not isinstance(meta[key], str):
            return f"meta.{key} must be a text, got {_shown(meta[key])}"
    return None


def _shown(value) -> str:
    """A short description of a metadata value for a message."""
    if isinstance(value, dict | list):
        return f"a {'mapping' if isinstance(value, dict) else 'list'} ({json.dumps(value)[:40]}...)"
    return "null" if value is None else repr(value)[:60]


def range_problem(time: np.ndarray, portal: np.ndarray, ranges: np.ndarray) -> str | None:
    """Why portal coordinates are physically impossible for a portal with these joint ranges (5, 2), or None."""
    tol = np.asarray(RANGE_TOLERANCE)
    out = (portal < ranges[:, 0] - tol) | (portal > ranges[:, 1] + tol)
    if not out.any():
        return None
    i, j = np.argwhere(out)[0]
    lo, hi, unit = ranges[j, 0], ranges[j, 1], UNITS[j]
    rows = int(out.any(axis=1).sum())
    return (
        f"{COORDINATES[j]} = {portal[i, j]:.6g} {unit} at sample {i} (t = {time[i]:.6g} s) is outside the "
        f"portal's range [{lo:.4g}, {hi:.4g}] {unit}; {rows} of {len(portal)} samples are out of range"
    )


def npz_members(fh: BinaryIO) -> None:
    """Refuse an archive that is not a zip or would decompress beyond MAX_TRAJECTORY_BYTES (ValueError)."""
    if not zipfile.is_zipfile(fh):
        raise ValueError("not a .npz archive")
    fh.seek(0)
    with zipfile.ZipFile(fh) as zf:
        infos = zf.infolist()
        total = sum(info.file_size for info in infos)
        if total > MAX_TRAJECTORY_BYTES:
            raise ValueError(f"its arrays decompress to {total:,} bytes, at most {MAX_TRAJECTORY_BYTES:,} are read")
        for info in infos:
            if info.filename.removesuffix(".npy") in ARRAYS:
                _npy_header(zf, info)
    fh.seek(0)


def _npy_header(zf: zipfile.ZipFile, info: zipfile.ZipInfo) -> None:
    """Refuse a member that is not a .npy array or declares more bytes than MAX_TRAJECTORY_BYTES."""
    name = info.filename.removesuffix(".npy")
    try:
        with zf.open(info) as member:
            version = np.lib.format.read_magic(member)
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, _, dtype = read(member)
    except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error, NotImplementedError) as e:
        raise ValueError(f"{name} is not a .npy array ({' '.join(str(e).split())[:80]})") from None
    size = math.prod(shape) * dtype.itemsize
    if size > MAX_TRAJECTORY_BYTES:
        raise ValueError(f"{name} declares shape {shape} ({size:,} bytes), at most {MAX_TRAJECTORY_BYTES:,} are read")


def parse_meta(array: np.ndarray) -> dict:
    """The metadata JSON object stored as a 0-d text array; ValueError if it is not one."""
    if not isinstance(array, np.ndarray) or array.dtype.kind != "U" or array.ndim != 0:
        got = f"dtype {array.dtype}, shape {array.shape}" if isinstance(array, np.ndarray) else "raw bytes"
        raise ValueError(f"meta must be one JSON text, got {got}")
    text = str(array)
    if len(text) > MAX_META_CHARS:
        raise ValueError(f"meta is {len(text):,} characters long, at most {MAX_META_CHARS:,} are read")
    try:
        meta = json.loads(text)
    except RecursionError:
        raise ValueError(f"meta JSON is nested more than {MAX_META_DEPTH} levels deep") from None
    except json.JSONDecodeError as e:
        raise ValueError(f"meta is not valid JSON ({e})") from None
    stack = [(meta, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_META_DEPTH:
            raise ValueError(f"meta JSON is nested more than {MAX_META_DEPTH} levels deep")
        children = node.values() if isinstance(node, dict) else node if isinstance(node, list) else ()
        stack += [(c, depth + 1) for c in children if isinstance(c, dict | list)]
    if not isinstance(meta, dict):
        raise ValueError(f"meta must be a JSON object, got {type(meta).__name__}")
    return meta
