"""Tracked scope poses (CSV) to trajectories, through inverse portal kinematics, with a report of rejections."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..model.portal import mat_to_quat, portal_from_shaft, quat_to_mat, shaft_pose, wrap
from ..spec import spec_hash, task_hash
from ..spec.limits import MAX_POSE_BYTES, MAX_POSE_ROWS, MAX_POSE_SECONDS, open_regular
from .instrument_poses import instrument_columns, instrument_poses, instruments_from_poses
from .trajectory import Trajectory, TrajectoryError

COLUMNS = ("time", "x", "y", "z", "qw", "qx", "qy", "qz", "cable")  # s, m (x3), quaternion wxyz, rad
QUAT_NORM_TOLERANCE = 0.01  # |norm - 1| above this is not a rotation
RANGE_SLACK = 1e-3  # rad or m past a joint limit still accepted (then clipped), as soft limits allow
REASONS = {
    "non_finite": "missing or non-finite value",
    "quaternion": f"quaternion norm differs from 1 by more than {QUAT_NORM_TOLERANCE}",
    "misses_portal": "shaft axis misses the portal point by more than the tolerance",
    "axis_angle": "orientation's shaft axis and the portal->tip direction differ by more than the tolerance",
    "out_of_range": "pitch, yaw or insertion outside the scope's joint ranges",
    "time": "time not after the previous accepted sample",
}


class PoseError(ValueError):
    """A pose file that cannot be read or imported; the message names the file and why."""

    def __init__(self, message: str, report: PoseReport | None = None, details: list[str] | None = None):
        super().__init__(message)
        self.report = report
        self.details = details if details is not None else (report.lines() if report else [])


@dataclass
class PoseReport:
    """What an import kept and rejected: row indices per reason, residuals of the kept rows."""

    rows: int
    kept: int
    rejected: dict[str, list[int]] = field(default_factory=dict)  # reason -> 0-based row indices
    max_miss_mm: float = 0.0
    max_angle_deg: float = 0.0

    def lines(self, labels=None, unit: str = "rows", first: int = 5) -> list[str]:
        """Human-readable summary; labels maps a row index to what to print (e.g. its CSV line)."""
        label = (lambda i: str(labels[i])) if labels is not None else (lambda i: str(i + 1))
        out = [
            f"{self.kept} of {self.rows} samples kept, {self.rows - self.kept} rejected"
            + (
                f"; kept samples: axis misses the portal by <= {self.max_miss_mm:.2f} mm, "
                f"axis angle <= {self.max_angle_deg:.2f} deg"
                if self.kept
                else ""
            )
        ]
        for reason, rows in self.rejected.items():
            shown = ", ".join(label(i) for i in rows[:first]) + (", ..." if len(rows) > first else "")
            out.append(f"  {len(rows)} x {REASONS[reason]} ({reason}): {unit} {shown}")
        return out


def poses_from_portal(task, time: np.ndarray, portal: np.ndarray, instruments: np.ndarray | None = None) -> np.ndarray:
    """Pose table (T, 9) in COLUMNS order from portal coordinates (T, 5), then the other instruments' columns
    (instrument_columns) if their coordinates are given: what a tracker would report."""
    tip, rot = shaft_pose(task.portal_point, task.portal_rot, portal)
    table = np.column_stack([time, tip, mat_to_quat(rot), wrap(np.asarray(portal, float)[:, 4])])
    return table if instruments is None else np.column_stack([table, instrument_poses(task, instruments)])


def portal_from_poses(
    task, poses: np.ndarray, tolerance_mm: float = 2.0, tolerance_deg: float = 5.0, max_rejected: float = 0.2
) -> tuple[np.ndarray, np.ndarray, PoseReport]:
    """Times (K,), portal coordinates (K, 5) of the consistent rows of a pose table, and the report. A table with the
    task's instrument columns after COLUMNS also gives their coordinates: (times, portal, instruments, report).

    Rejected rows (a check failing for the scope or any instrument) are dropped; PoseError if fewer than 2 remain
    or more than max_rejected of them go.
    """
    with np.errstate(over="ignore", invalid="ignore"):  # rows of 1e300 overflow: rejected, not warned about
        return _portal_from_poses(task, poses, tolerance_mm, tolerance_deg, max_rejected)


def _portal_from_poses(task, poses, tolerance_mm: float, tolerance_deg: float, max_rejected: float):
    """portal_from_poses, without its floating-point error state."""
    poses = np.asarray(poses, float)
    tools = len(instrument_columns(task)) if task.instruments else 0
    if poses.ndim != 2 or poses.shape[1] not in {len(COLUMNS), len(COLUMNS) + tools}:
        raise ValueError(f"a pose table has shape (T, {len(COLUMNS)}) in the order {COLUMNS}, got {poses.shape}")
    tracked = poses.shape[1] > len(COLUMNS)
    if tracked:
        instruments, tool_bad = instruments_from_poses(task, poses[:, len(COLUMNS) :], tolerance_mm, tolerance_deg)
        poses = poses[:, : len(COLUMNS)]
    n = len(poses)
    bad: dict[str, np.ndarray] = {}
    finite = np.all(np.isfinite(poses), axis=1)
    bad["non_finite"] = ~finite
    safe = np.where(finite[:, None], poses, [0, 0, 0, 1, 1, 0, 0, 0, 0])
    norm = np.linalg.norm(safe[:, 4:8], axis=1)
    bad["quaternion"] = finite & (np.abs(norm - 1) > QUAT_NORM_TOLERANCE)
    q4, miss, angle = portal_from_shaft(task.portal_point, task.portal_rot, safe[:, 1:4], quat_to_mat(safe[:, 4:8]))
    usable = finite & ~bad["quaternion"]
    bad["misses_portal"] = usable & (miss > tolerance_mm / 1000)
    bad["axis_angle"] = usable & (angle > math.radians(tolerance_deg))
    lo, hi = task.ranges[:3, 0] - RANGE_SLACK, task.ranges[:3, 1] + RANGE_SLACK
    bad["out_of_range"] = usable & np.any((q4[:, :3] < lo) | (q4[:, :3] > hi), axis=1)
    if tracked:
        for reason, rows in tool_bad.items():
            bad[reason] = bad[reason] | rows
    ok = ~np.any(list(bad.values()), axis=0)
    bad["time"] = np.zeros(n, bool)
    last = -np.inf
    for i in np.flatnonzero(ok):
        if poses[i, 0] <= last:
            bad["time"][i], ok[i] = True, False
        else:
            last = poses[i, 0]
    report = PoseReport(
        n,
        int(ok.sum()),
        {k: np.flatnonzero(v).tolist() for k, v in bad.items() if v.any()},
        float(miss[ok].max() * 1000) if ok.any() else 0.0,
        float(np.degrees(angle[ok].max())) if ok.any() else 0.0,
    )
    if report.kept < 2 or n - report.kept > max_rejected * n:
        raise PoseError(
            f"{n - report.kept} of {n} samples rejected (at most {max_rejected:.0%} may be, and 2 must remain)", report
        )
    portal = np.column_stack([q4[ok], wrap(poses[ok, 8])])
    portal[:, :3] = np.clip(portal[:, :3], task.ranges[:3, 0], task.ranges[:3, 1])
    return (poses[ok, 0], portal, instruments[ok], report) if tracked else (poses[ok, 0], portal, report)


def duration_problem(time: np.ndarray, hz: float | None) -> str | None:
    """Why kept samples span too long a time (or, resampled at hz, too many samples), or None."""
    span = float(time[-1] - time[0])
    hint = "is the time column in seconds?"
    if not math.isfinite(span) or span > MAX_POSE_SECONDS:
        return f"the samples span {span:.3g} s (t = {time[0]:.6g} to {time[-1]:.6g}), more than a day: {hint}"
    n = math.floor(span * hz + 1e-9) + 1 if hz else len(time)
    if n < 2:
        return f"the samples span {span:.3g} s, less than one sample period at {hz:g} Hz: {hint}"
    if n > MAX_POSE_ROWS:
        return f"{span:.6g} s at {hz:g} Hz is {n:,} samples, at most {MAX_POSE_ROWS:,} are allowed: {hint}"
    return None


def resample(time: np.ndarray, portal: np.ndarray, hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Portal coordinates linearly interpolated at t0 + k / hz (angles roll and cable unwrapped first)."""
    problem = duration_problem(time, hz)
    if problem:
        raise PoseError(problem)
    grid = time[0] + np.arange(int(math.floor((time[-1] - time[0]) * hz + 1e-9)) + 1) / hz
    q = portal.copy()
    q[:, 3:] = np.unwrap(q[:, 3:], axis=0)
    out = resample_columns(grid, time, q)
    out[:, 3:] = wrap(out[:, 3:])
    return grid, out


def resample_columns(grid: np.ndarray, time: np.ndarray, values: np.ndarray | None) -> np.ndarray | None:
    """Every column of (T, ...) `values` linearly interpolated at `grid` (instruments' coordinates; None stays)."""
    if values is None:
        return None
    flat = values.reshape(len(time), -1)
    out = np.column_stack([np.interp(grid, time, flat[:, j]) for j in range(flat.shape[1])])
    return out.reshape(len(grid), *values.shape[1:])


def resample_bodies(grid: np.ndarray, time: np.ndarray, bodies: np.ndarray | None) -> np.ndarray | None:
    """(T, k, 7) free bodies at `grid`: positions linearly, quaternions normalised after linear interpolation
    along the short way (signs aligned sample to sample first); None stays None."""
    if bodies is None:
        return None
    quat = bodies[..., 3:].copy()
    flips = np.sign(np.einsum("tkq,tkq->tk", quat[1:], quat[:-1]))
    flips[flips == 0] = 1.0
    quat[1:] *= np.cumprod(flips, axis=0)[..., None]
    out = resample_columns(grid, time, np.concatenate([bodies[..., :3], quat], axis=-1))
    out[..., 3:] /= np.linalg.norm(out[..., 3:], axis=-1, keepdims=True)
    return out


def read_pose_csv(path: Path, optional: Sequence[str] = ()) -> tuple[np.ndarray, list[int]]:
    """Pose table (T, 9) in COLUMNS order, then the `optional` columns (other instruments) if the header has them
    all, and the file line of each row; PoseError names file and line (and columns of a partial optional set)."""
    path = Path(path)
    try:
        fh = open_regular(path, MAX_POSE_BYTES)  # never blocks on a FIFO; refuses folders and huge files
    except ValueError as e:
        raise PoseError(f"{path}: {e}") from None
    try:
        with io.TextIOWrapper(fh, encoding="utf-8-sig", newline="") as f:  # -sig: a spreadsheet's byte-order mark
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None:
                raise PoseError(f"{path}: empty file (expected a header row {','.join(COLUMNS)})")
            names = [h.strip().lower() for h in header]
            missing = [c for c in COLUMNS if c not in names]
            if missing:
                raise PoseError(f"{path}:1: missing columns {missing} (header has {names})")
            extra = [c for c in optional if c in names]
            if extra and len(extra) < len(optional):
                missing = [c for c in optional if c not in names]
                raise PoseError(f"{path}:1: missing instrument columns {missing} (the file tracks {extra})")
            wanted = (*COLUMNS, *extra)
            cols = [names.index(c) for c in wanted]
            rows, lines = [], []
            for cells in reader:
                if not cells or not any(c.strip() for c in cells):
                    continue
                if len(cells) != len(names):
                    raise PoseError(f"{path}:{reader.line_num}: {len(cells)} fields, the header has {len(names)}")
                if len(rows) == MAX_POSE_ROWS:
                    raise PoseError(f"{path}:{reader.line_num}: more than {MAX_POSE_ROWS:,} samples")
                rows.append([_number(cells[j], path, reader.line_num, wanted[k]) for k, j in enumerate(cols)])
                lines.append(reader.line_num)
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise PoseError(f"{path}: cannot read ({e})") from None
    if not rows:
        raise PoseError(f"{path}: no samples after the header")
    return np.array(rows), lines


def _number(cell: str, path: Path, line: int, column: str) -> float:
    """A CSV cell as a float; an empty cell is NaN (a tracking dropout, rejected later)."""
    cell = cell.strip()
    if not cell:
        return math.nan
    try:
        return float(cell)
    except ValueError:
        raise PoseError(f"{path}:{line}: column {column!r}: {cell!r} is not a number") from None


def import_poses(
    task,
    path: Path,
    meta: dict,
    tolerance_mm: float = 2.0,
    tolerance_deg: float = 5.0,
    max_rejected: float = 0.2,
    resample_hz: float | None = None,
) -> tuple[Trajectory, list[str]]:
    """A Trajectory from a pose CSV, and the report lines; PoseError (with the report) if it cannot be made."""
    path = Path(path)
    poses, lines = read_pose_csv(path, instrument_columns(task) if task.instruments else ())
    try:
        time, portal, *instruments, report = portal_from_poses(task, poses, tolerance_mm, tolerance_deg, max_rejected)
    except PoseError as e:
        raise PoseError(f"{path}: {e}", e.report, e.report.lines(lines, "lines")) from None
    instruments = instruments[0] if instruments else None
    text = report.lines(lines, "lines")
    if task.instruments:
        names = ", ".join(i.spec.name for i in task.instruments)
        text.append(f"instruments {names}: " + ("tracked" if instruments is not None else "not in the file, at rest"))
    problem = duration_problem(time, resample_hz)
    if problem:
        raise PoseError(f"{path}: {problem}", report, text)
    if resample_hz:
        raw, before = len(time), time
        time, portal = resample(time, portal, resample_hz)
        instruments = resample_columns(time, before, instruments)
        text.append(f"resampled {raw} samples to {len(time)} at {resample_hz:g} Hz (one per control step)")
    meta = {
        "spec": task.spec.name,
        "spec_hash": spec_hash(task.spec),
        "task_hash": task_hash(task.spec),
        "source": "human",
        "imported_from": path.name,
        "samples": report.rows,
        "rejected": report.rows - report.kept,
        "rejected_by_reason": {k: len(v) for k, v in report.rejected.items()},
        "time_offset": float(time[0]),
        **meta,
    }
    try:
        return Trajectory(time - time[0], portal, meta, instruments=instruments), text
    except TrajectoryError as e:
        raise PoseError(f"{path}: {e}", report, text) from None
