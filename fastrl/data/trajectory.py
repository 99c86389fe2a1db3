"""The trajectory contract: time-stamped portal coordinates and/or video frames (+ actions, metadata) in one .npz."""

from __future__ import annotations

import json
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..atomic import atomic_write
from ..spec.limits import MAX_TRAJECTORY_BYTES, open_regular
from .checks import (
    COORDINATES,
    frames_array,
    meta_problem,
    npz_members,
    parse_meta,
    range_problem,
    real_array,
    time_problem,
)

SOURCES = ("agent", "expert", "human", "synthetic")
__all__ = ["COORDINATES", "SOURCES", "VIDEO_ONLY", "Trajectory", "TrajectoryError", "load_files", "load_trajectories"]
VIDEO_ONLY = "is video only (frames, no portal coordinates): replay and kinematic scores need portal coordinates"


def recorded_seed(meta: dict) -> int:
    """The episode seed a recording's metadata gives (its targets, its start); 0 where it gives none."""
    return int(meta.get("seed", 0))


class TrajectoryError(ValueError):
    """A trajectory file that does not follow the contract; the message says why."""


@dataclass
class Trajectory:
    """Portal coordinates (or endoscope frames) over time; observations and features are recomputed by replay."""

    time: np.ndarray  # (T,) seconds, increasing
    portal: np.ndarray | None  # (T, 5) [pitch, yaw, insertion, roll, cable]; None: a video-only trajectory
    meta: dict = field(default_factory=dict)  # spec, spec_hash, subject, skill, source, seed, ...
    actions: np.ndarray | None = None  # (T-1, ...) actions between samples, where known
    instruments: np.ndarray | None = None  # (T, n) every instrument's portal coordinates, in spec order, if any
    bodies: np.ndarray | None = None  # (T, k, 7) LooseBodies' free bodies: position and quaternion (wxyz), if any
    frames: np.ndarray | None = None  # (T, H, W, 3) uint8 endoscope video frames shown at `time`, if any

    def __post_init__(self):
        try:
            self.time = real_array(self.time, "time")
            if self.portal is not None:
                self.portal = real_array(self.portal, "portal")
            if self.frames is not None:
                self.frames = frames_array(self.frames)
            if self.actions is not None:
                self.actions = np.asarray(self.actions)
                real_array(self.actions, "actions")
            if self.instruments is not None:
                self.instruments = real_array(self.instruments, "instruments")
            if self.bodies is not None:
                self.bodies = real_array(self.bodies, "bodies")
        except ValueError as e:
            raise TrajectoryError(str(e)) from None
        problem = self.problem()
        if problem:
            raise TrajectoryError(problem)

    @property
    def seed(self) -> int:
        """The episode seed the recording was made with (its targets, its start); 0 where the file gives none."""
        return recorded_seed(self.meta)

    def problem(self) -> str | None:
        """Why this trajectory breaks the contract, or None."""
        if self.time.ndim != 1 or len(self.time) < 2:
            return f"time must have shape (T,) with T >= 2, got {self.time.shape}"
        if self.portal is None and self.frames is None:
            return "holds neither portal coordinates nor video frames"
        if self.portal is not None and self.portal.shape != (len(self.time), 5):
            return f"portal must have shape ({len(self.time)}, 5), got {self.portal.shape}"
        if self.frames is not None and (self.frames.ndim != 4 or self.frames.shape[::3] != (len(self.time), 3)):
            return f"frames must have shape ({len(self.time)}, H, W, 3), got {self.frames.shape}"
        portal = self.portal if self.portal is not None else np.zeros((len(self.time), 5))
        if not (np.all(np.isfinite(self.time)) and np.all(np.isfinite(portal))):
            rows = np.where(~np.isfinite(portal).all(1) | ~np.isfinite(self.time))[0]
            return f"non-finite values in rows {rows[:5].tolist()}{'...' if len(rows) > 5 else ''}"
        if self.instruments is not None and (self.instruments.ndim != 2 or len(self.instruments) != len(self.time)):
            return f"instruments must have shape ({len(self.time)}, n), got {self.instruments.shape}"
        if self.instruments is not None and not np.all(np.isfinite(self.instruments)):
            return "instruments hold non-finite values"
        if self.bodies is not None and (self.bodies.ndim != 3 or self.bodies.shape[::2] != (len(self.time), 7)):
            return f"bodies must have shape ({len(self.time)}, k, 7), got {self.bodies.shape}"
        if self.bodies is not None and not np.all(np.isfinite(self.bodies)):
            return "bodies hold non-finite values"
        if np.any(np.diff(self.time) <= 0):
            return "time must increase strictly"
        problem = time_problem(self.time)
        if problem:
            return problem
        if self.actions is not None and (self.actions.ndim == 0 or len(self.actions) != len(self.time) - 1):
            return f"actions must have T-1 = {len(self.time) - 1} rows, got shape {self.actions.shape}"
        if self.actions is not None and not np.all(np.isfinite(self.actions)):
            return "actions hold non-finite values"
        problem = meta_problem(self.meta)
        if problem:
            return problem
        if self.meta.get("source", "agent") not in SOURCES:
            return f"meta.source must be one of {SOURCES}, got {self.meta.get('source')!r}"
        return None

    def range_problem(self, ranges: np.ndarray) -> str | None:
        """Why these coordinates are impossible for a portal with joint ranges (5, 2), naming the first one, or None
        (a video-only trajectory has no coordinates to replay: VIDEO_ONLY)."""
        if self.portal is None:
            return VIDEO_ONLY
        return range_problem(self.time, self.portal, np.asarray(ranges, float))

    def save(self, path: Path) -> Path:
        """Write the .npz (meta as a JSON string) atomically: a kill leaves the old file or the new one."""
        arrays = {"time": self.time, "meta": np.array(json.dumps(self.meta))}
        if self.portal is not None:
            arrays["portal"] = self.portal
        if self.actions is not None:
            arrays["actions"] = np.asarray(self.actions)
        if self.instruments is not None:
            arrays["instruments"] = self.instruments
        if self.bodies is not None:
            arrays["bodies"] = self.bodies
        if self.frames is not None:
            arrays["frames"] = self.frames
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        return atomic_write(path, lambda f: np.savez_compressed(f, **arrays))

    @classmethod
    def load(cls, path: Path) -> Trajectory:
        """Read and check a .npz; TrajectoryError names the file and the problem (never blocks on a FIFO)."""
        path = Path(path)
        try:
            with open_regular(path, MAX_TRAJECTORY_BYTES) as fh:
                npz_members(fh)
                with np.load(fh, allow_pickle=False) as z:
                    need = {"time", "meta"} | ({"portal"} if "frames" not in z.files else set())
                    missing = need - set(z.files)
                    if missing:
                        raise TrajectoryError(f"{path}: missing arrays {sorted(missing)}")
                    meta = parse_meta(z["meta"])
                    actions = z["actions"] if "actions" in z.files else None
                    instruments = z["instruments"] if "instruments" in z.files else None
                    bodies = z["bodies"] if "bodies" in z.files else None
                    frames = z["frames"] if "frames" in z.files else None
                    time, portal = z["time"], z["portal"] if "portal" in z.files else None
        except TrajectoryError:
            raise
        except (OSError, ValueError, zipfile.BadZipFile, EOFError, KeyError, zlib.error, NotImplementedError) as e:
            raise TrajectoryError(f"{path}: {_reason(e)}") from None
        try:
            return cls(time, portal, meta, actions, instruments, bodies, frames)
        except TrajectoryError as e:
            raise TrajectoryError(f"{path}: {e}") from None


def _reason(error: Exception) -> str:
    """What went wrong reading a file, in one line."""
    if isinstance(error, OSError):
        return f"cannot read file: {error.strerror or error}"
    text = " ".join(str(error).split())
    if "pickled" in text:
        return "holds pickled Python objects (an object array), which are never loaded"
    plain = isinstance(error, ValueError) and not isinstance(error, zipfile.BadZipFile)
    return text if plain and text else f"not a readable trajectory file ({text or type(error).__name__})"


def load_files(files, ranges: np.ndarray | None = None) -> tuple[list[tuple[Path, Trajectory]], list[str]]:
    """Load each file (and, given joint ranges (5, 2), check its coordinates); bad files become messages."""
    good, errors = [], []
    for f in map(Path, files):
        try:
            traj = Trajectory.load(f)
            problem = traj.range_problem(ranges) if ranges is not None else None
            if problem:
                raise TrajectoryError(f"{f}: {problem}")
            good.append((f, traj))
        except TrajectoryError as e:
            errors.append(str(e))
    return good, errors


def load_trajectories(paths, ranges: np.ndarray | None = None) -> tuple[list[Trajectory], list[str]]:
    """Load every .npz under the given files or folders; bad files become messages naming them, the rest load."""
    files = []
    for p in map(Path, paths):
        files += sorted(p.glob("*.npz")) if p.is_dir() else [p]
    good, errors = load_files(files, ranges)
    return [traj for _, traj in good], errors
