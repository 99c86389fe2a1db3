"""Project world points into the endoscope image and draw a path on it."""

from __future__ import annotations

import math

import numpy as np


def project_points(
    points: np.ndarray, cam_pos: np.ndarray, cam_mat: np.ndarray, fovy_deg: float, width: int, height: int
) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (n, 2: column, row) of world points and a mask of those in front of the camera."""
    local = (np.asarray(points, float) - cam_pos) @ np.asarray(cam_mat, float).reshape(3, 3)  # right, up, back
    ahead = -local[:, 2]
    focal = 0.5 * height / math.tan(0.5 * math.radians(fovy_deg))
    safe = np.where(ahead > 1e-6, ahead, 1.0)
    uv = np.stack([0.5 * width + focal * local[:, 0] / safe, 0.5 * height - focal * local[:, 1] / safe], axis=1)
    return uv, ahead > 1e-6


def draw_path(image: np.ndarray, uv: np.ndarray, front: np.ndarray, colour, width: int = 1) -> np.ndarray:
    """Draw the polyline through the visible pixel coordinates onto a copy of the image."""
    out = image.copy()
    h, w = out.shape[:2]
    for (a, b), ok in zip(zip(uv[:-1], uv[1:]), front[:-1] & front[1:]):
        if not ok:
            continue
        n = int(max(abs(b - a).max(), 1.0)) + 1
        pts = np.linspace(a, b, n)
        for dy in range(-(width // 2), width - width // 2):
            for dx in range(-(width // 2), width - width // 2):
                c, r = np.round(pts[:, 0]).astype(int) + dx, np.round(pts[:, 1]).astype(int) + dy
                keep = (c >= 0) & (c < w) & (r >= 0) & (r < h)
                out[r[keep], c[keep]] = colour
    return out
