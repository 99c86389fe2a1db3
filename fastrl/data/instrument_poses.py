"""Tracked instrument poses (a probe's or a grasper's shaft, beside the scope's) to and from portal coordinates."""

from __future__ import annotations

import math

import numpy as np

from ..model.portal import mat_to_quat, portal_from_shaft, quat_to_mat, shaft_pose

POSE = ("x", "y", "z", "qw", "qx", "qy", "qz")  # the shaft's distal end: m (x3), quaternion wxyz
RANGE_SLACK = 1e-3  # rad or m past a joint limit still accepted (then clipped), as for the scope


def instrument_columns(task) -> list[str]:
    """CSV columns of the task's instruments in spec order: NAME_x .. NAME_qz, and NAME_jaw (rad) for a grasper."""
    cols = []
    for inst in task.instruments:
        cols += [f"{inst.spec.name}_{c}" for c in POSE]
        cols += [f"{inst.spec.name}_jaw"] if len(inst.qadr) == 5 else []
    return cols


def instrument_poses(task, instruments: np.ndarray) -> np.ndarray:
    """Pose table (T, len(instrument_columns)) from instrument coordinates (T, n): what a tracker would report."""
    out, start = [], 0
    for inst in task.instruments:
        k = len(inst.qadr)
        q = np.asarray(instruments, float)[:, start : start + k]
        tip, rot = shaft_pose(inst.point, inst.rot, np.column_stack([q[:, :4], np.zeros(len(q))]))
        out += [tip, mat_to_quat(rot)] + ([q[:, 4:5]] if k == 5 else [])
        start += k
    return np.column_stack(out)


def instruments_from_poses(
    task, table: np.ndarray, tolerance_mm: float, tolerance_deg: float
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Instrument coordinates (T, n) from a pose table in instrument_columns order, and the rows each check rejects
    (reasons as the scope's: non_finite, quaternion, misses_portal, axis_angle, out_of_range), over all instruments."""
    table = np.asarray(table, float)
    n = len(table)
    bad = {k: np.zeros(n, bool) for k in ("non_finite", "quaternion", "misses_portal", "axis_angle", "out_of_range")}
    coords, col = [], 0
    for inst in task.instruments:
        k = len(inst.qadr)
        block = table[:, col : col + len(POSE) + (k == 5)]
        col += block.shape[1]
        finite = np.all(np.isfinite(block), axis=1)
        safe = np.where(finite[:, None], block, [0, 0, 0, 1, 0, 0, 0] + [0] * (k == 5))
        quat_bad = finite & (np.abs(np.linalg.norm(safe[:, 3:7], axis=1) - 1) > 0.01)
        q4, miss, angle = portal_from_shaft(inst.point, inst.rot, safe[:, :3], quat_to_mat(safe[:, 3:7]))
        usable = finite & ~quat_bad
        lo, hi = inst.ranges[:, 0] - RANGE_SLACK, inst.ranges[:, 1] + RANGE_SLACK
        q = np.column_stack([q4, safe[:, 7:8]]) if k == 5 else q4
        bad["non_finite"] |= ~finite
        bad["quaternion"] |= quat_bad
        bad["misses_portal"] |= usable & (miss > tolerance_mm / 1000)
        bad["axis_angle"] |= usable & (angle > math.radians(tolerance_deg))
        outside = np.any((q4[:, :3] < lo[:3]) | (q4[:, :3] > hi[:3]), axis=1)  # roll and jaw are clipped only
        bad["out_of_range"] |= usable & outside
        coords.append(np.clip(q, inst.ranges[:, 0], inst.ranges[:, 1]))
    return np.column_stack(coords), bad
