"""Kinematic scores of a tip path: pure functions of positions and times."""

from __future__ import annotations

import numpy as np


def path_length(tip: np.ndarray) -> float:
    """Distance travelled by the tip (m)."""
    return float(np.linalg.norm(np.diff(tip, axis=0), axis=1).sum())


def log_dimensionless_jerk(tip: np.ndarray, time: np.ndarray) -> float:
    """Smoothness: -ln(T^3 / v_peak^2 * integral |jerk|^2 dt) of the tip path; higher is smoother."""
    if len(time) < 4:
        return float("nan")
    vel = np.gradient(tip, time, axis=0)
    jerk = np.gradient(np.gradient(vel, time, axis=0), time, axis=0)
    duration = float(time[-1] - time[0])
    peak = float(np.linalg.norm(vel, axis=1).max())
    if peak <= 1e-9:
        return float("nan")  # the tip never moved: smoothness is undefined
    integral = float(np.trapezoid(np.sum(jerk**2, axis=1), time))
    return float(-np.log(max(duration**3 / peak**2 * integral, 1e-300)))


def deviation_by_progress(
    tip: np.ndarray, time: np.ndarray, reference: np.ndarray, ref_time: np.ndarray, bins: int = 100
) -> np.ndarray:
    """Distance to the reference path at each percent of the procedure (both paths time-normalised)."""
    u = np.linspace(0.0, 1.0, bins + 1)

    def at(path: np.ndarray, t: np.ndarray) -> np.ndarray:
        s = (t - t[0]) / max(t[-1] - t[0], 1e-9)
        return np.stack([np.interp(u, s, path[:, k]) for k in range(path.shape[1])], axis=1)

    return np.linalg.norm(at(tip, time) - at(reference, ref_time), axis=1)
