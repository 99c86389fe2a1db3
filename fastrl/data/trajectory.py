"""The trajectory contract: time-stamped portal coordinates (+ actions, metadata) in one .npz file."""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

SOURCES = ("agent", "expert", "human", "synthetic")
COORDINATES = ("pitch", "yaw", "insertion", "roll", "cable")  # rad, rad, m, rad, rad


class TrajectoryError(ValueError):
    """A trajectory file that does not follow the contract; the message says why."""


@dataclass
class Trajectory:
    """Portal coordinates over time; observations and features are recomputed by replay."""

    time: np.ndarray  # (T,) seconds, increasing
    portal: np.ndarray  # (T, 5) [pitch, yaw, insertion, roll, cable]
    meta: dict = field(default_factory=dict)  # spec, spec_hash, subject, skill, source, seed, ...
    actions: np.ndarray | None = None  # (T-1, ...) actions between samples, where known

    def __post_init__(self):
        self.time = np.asarray(self.time, float)
        self.portal = np.asarray(self.portal, float)
        problem = self.problem()
        if problem:
            raise TrajectoryError(problem)

    def problem(self) -> str | None:
        """Why this trajectory breaks the contract, or None."""
        if self.time.ndim != 1 or len(self.time) < 2:
            return f"time must have shape (T,) with T >= 2, got {self.time.shape}"
        if self.portal.shape != (len(self.time), 5):
            return f"portal must have shape ({len(self.time)}, 5), got {self.portal.shape}"
        if not (np.all(np.isfinite(self.time)) and np.all(np.isfinite(self.portal))):
            rows = np.where(~np.isfinite(self.portal).all(1) | ~np.isfinite(self.time))[0]
            return f"non-finite values in rows {rows[:5].tolist()}{'...' if len(rows) > 5 else ''}"
        if np.any(np.diff(self.time) <= 0):
            return "time must increase strictly"
        if self.actions is not None and len(self.actions) != len(self.time) - 1:
            return f"actions must have T-1 = {len(self.time) - 1} rows, got {len(self.actions)}"
        if self.meta.get("source", "agent") not in SOURCES:
            return f"meta.source must be one of {SOURCES}, got {self.meta.get('source')!r}"
        return None

    def save(self, path: Path) -> Path:
        """Write the .npz (meta as a JSON string)."""
        arrays = {"time": self.time, "portal": self.portal, "meta": np.array(json.dumps(self.meta))}
        if self.actions is not None:
            arrays["actions"] = np.asarray(self.actions)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(path, **arrays)
        return path

    @classmethod
    def load(cls, path: Path) -> Trajectory:
        """Read and check a .npz; TrajectoryError names the file and the problem."""
        path = Path(path)
        if path.exists() and not zipfile.is_zipfile(path):
            raise TrajectoryError(f"{path}: not a .npz archive")
        try:
            with np.load(path, allow_pickle=False) as z:
                missing = {"time", "portal", "meta"} - set(z.files)
                if missing:
                    raise TrajectoryError(f"{path}: missing arrays {sorted(missing)}")
                meta = json.loads(str(z["meta"]))
                actions = z["actions"] if "actions" in z.files else None
                time, portal = z["time"], z["portal"]
        except (OSError, ValueError, zipfile.BadZipFile, json.JSONDecodeError, EOFError) as e:
            if isinstance(e, TrajectoryError):
                raise
            raise TrajectoryError(f"{path}: not a readable trajectory file ({e})") from None
        if not isinstance(meta, dict):
            raise TrajectoryError(f"{path}: meta must be a JSON object")
        try:
            return cls(time, portal, meta, actions)
        except TrajectoryError as e:
            raise TrajectoryError(f"{path}: {e}") from None


def load_trajectories(paths) -> tuple[list[Trajectory], list[str]]:
    """Load every .npz under the given files or folders; bad files become messages, the rest load."""
    files = []
    for p in map(Path, paths):
        files += sorted(p.glob("*.npz")) if p.is_dir() else [p]
    good, errors = [], []
    for f in files:
        try:
            good.append(Trajectory.load(f))
        except TrajectoryError as e:
            errors.append(str(e))
    return good, errors
