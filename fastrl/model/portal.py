"""Closed-form portal kinematics of the scope: shaft pose <-> portal coordinates (numpy, no MjData).

The chain of model/scope.py: the pivot frame sits at the portal point with the portal rotation R0;
pitch turns about its x, then yaw about the new y; the shaft slides along z by the insertion and rolls
about z. The shaft frame's origin is the distal tip (where the camera sits), its z runs along the
shaft from the portal to the tip, its y is the camera head's image up (x = y cross z).
"""

from __future__ import annotations

import numpy as np

from ..spec import geometry as geo


def _rot(axis: int, a: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotations by angles a about the x (0), y (1) or z (2) axis."""
    c, s = np.cos(a), np.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.zeros((len(a), 3, 3))
    r[:, axis, axis] = 1.0
    r[:, i, i], r[:, j, j], r[:, i, j], r[:, j, i] = c, c, -s, s
    return r


def wrap(a):
    """Angles wrapped to [-pi, pi)."""
    return (np.asarray(a, float) + np.pi) % (2 * np.pi) - np.pi


def shaft_pose(point: np.ndarray, rot: np.ndarray, portal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tip positions (T, 3) and shaft rotations (T, 3, 3) at portal coordinates (T, 5)."""
    q = np.atleast_2d(np.asarray(portal, float))
    pivot = rot @ _rot(0, q[:, 0]) @ _rot(1, q[:, 1])
    tip = point + q[:, 2:3] * pivot[:, :, 2]
    return tip, pivot @ _rot(2, q[:, 3])


def portal_from_shaft(
    point: np.ndarray, rot: np.ndarray, tip: np.ndarray, shaft: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pitch, yaw, insertion, roll (T, 4) from tip positions and shaft rotations; also miss (m), angle (rad).

    Pitch, yaw and insertion come from the tip position (the line portal -> tip is the shaft axis), roll
    from the rotation about that axis. `miss` is how far the portal point lies from the shaft line of the
    rotation (through the tip along its z); `angle` is between that z and the direction portal -> tip.
    """
    d = (np.asarray(tip, float) - point) @ rot  # portal -> tip in the pivot rest frame
    insertion = np.linalg.norm(d, axis=1)
    axis = d / np.maximum(insertion, 1e-12)[:, None]
    yaw = np.arcsin(np.clip(axis[:, 0], -1.0, 1.0))
    pitch = np.arctan2(-axis[:, 1], axis[:, 2])
    local = rot.T @ np.asarray(shaft, float)  # R0^T R
    n = np.swapaxes(_rot(0, pitch) @ _rot(1, yaw), 1, 2) @ local  # ~ Rz(roll)
    roll = np.arctan2(n[:, 1, 0] - n[:, 0, 1], n[:, 0, 0] + n[:, 1, 1])
    z = local[:, :, 2]
    along = np.sum(d * z, axis=1)
    miss = np.linalg.norm(d - along[:, None] * z, axis=1)
    angle = np.arctan2(np.linalg.norm(np.cross(axis, z), axis=1), np.sum(axis * z, axis=1))
    return np.column_stack([pitch, yaw, insertion, roll]), miss, angle


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    """(T, 3, 3) rotations from (T, 4) quaternions w, x, y, z (normalised first)."""
    q = np.asarray(q, float)
    w, x, y, z = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        1,
    )


def mat_to_quat(m: np.ndarray) -> np.ndarray:
    """(T, 4) unit quaternions w, x, y, z (w >= 0) from (T, 3, 3) rotations."""
    return np.array([geo.mat_to_quat(r) for r in m]).reshape(-1, 4)
