"""Video frames on the control grid: each control tick takes the frame nearest in time (ties: the earlier one)."""

from __future__ import annotations

import math

import numpy as np

TIME_SLACK = 1e-9  # s of float rounding: a tick this close past the last frame falls on it; ties go earlier


def control_grid(time: np.ndarray, hz: float) -> np.ndarray:
    """The ticks t0 + k / hz from the first sample to the last (inclusive)."""
    return time[0] + np.arange(math.floor((time[-1] - time[0]) * hz + TIME_SLACK) + 1) / hz


def nearest_rows(grid: np.ndarray, time: np.ndarray, values: np.ndarray | None) -> np.ndarray | None:
    """The row of (T, ...) `values` nearest in time to each tick of `grid` (ties: the earlier row); None stays."""
    if values is None:
        return None
    after = np.clip(np.searchsorted(time, grid, side="left"), 1, len(time) - 1)
    before = after - 1
    take = np.where(grid - time[before] <= time[after] - grid + TIME_SLACK, before, after)
    return values[take]
