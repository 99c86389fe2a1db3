"""The liver tour's ground-truth metrics (the paper's Table 3): economy, safety and contacts of a camera path."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from scipy.spatial import cKDTree


def inside_cavity(cam: np.ndarray, radius: float) -> np.ndarray:
    """(T,) whether each camera position is inside the abdominal wall and above the posterior wall."""
    return (np.linalg.norm(cam, axis=1) < radius) & (cam[:, 2] > 0.0)


def economy(cam: np.ndarray, radius: float) -> float:
    """Total distance (m) the camera covers inside the cavity: steps between two inside samples."""
    if len(cam) < 2:
        return 0.0
    inside = inside_cavity(cam, radius)
    steps = np.linalg.norm(np.diff(cam, axis=0), axis=1)
    return float(steps[inside[1:] & inside[:-1]].sum())


def safety(cam: np.ndarray, anatomy: cKDTree) -> float:
    """Sum over samples of the distance (m) from the camera to the closest anatomy vertex."""
    if len(cam) == 0:
        return 0.0
    return float(anatomy.query(cam)[0].sum())


def contact_samples(contacts) -> int:
    """Samples at which the scope touched anatomy or walls."""
    return int((np.asarray(contacts) > 0).sum())


def tour_metrics(cam: np.ndarray, contacts, anatomy: cKDTree, radius: float) -> dict[str, float]:
    """Economy, safety and contacts of one camera path."""
    return {"economy": economy(cam, radius), "safety": safety(cam, anatomy), "contacts": contact_samples(contacts)}
