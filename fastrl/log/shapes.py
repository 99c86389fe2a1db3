"""Numpy shapes and colours for the recording: shell, disk, rings, a viridis ramp."""

from __future__ import annotations

import numpy as np

# viridis at 9 evenly spaced stops (sRGB 0..255)
_VIRIDIS = np.array(
    [
        [68, 1, 84],
        [71, 44, 122],
        [59, 81, 139],
        [44, 113, 142],
        [33, 144, 141],
        [39, 173, 129],
        [92, 200, 99],
        [170, 220, 50],
        [253, 231, 37],
    ],
    float,
)


def hemisphere(
    radius: float, holes: list[tuple[np.ndarray, float]] = (), n_lat: int = 14, n_lon: int = 56
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Upper hemisphere: vertices, outward normals, CCW triangles; minus (dir, angle) holes."""
    el = np.linspace(0.0, 0.5 * np.pi, n_lat + 1)
    az = np.linspace(0.0, 2 * np.pi, n_lon + 1)[:-1]
    E, A = np.meshgrid(el[:-1], az, indexing="ij")
    dirs = np.stack([np.cos(E) * np.cos(A), np.cos(E) * np.sin(A), np.sin(E)], -1).reshape(-1, 3)
    dirs = np.vstack([dirs, [[0.0, 0.0, 1.0]]])
    pole = len(dirs) - 1
    i, j = np.meshgrid(np.arange(n_lat - 1), np.arange(n_lon), indexing="ij")
    a, b = i * n_lon + j, i * n_lon + (j + 1) % n_lon
    c, d = a + n_lon, b + n_lon
    quads = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    top_a = (n_lat - 1) * n_lon + np.arange(n_lon)
    cap = np.stack([top_a, (n_lat - 1) * n_lon + (np.arange(n_lon) + 1) % n_lon, np.full(n_lon, pole)], -1)
    tris = np.concatenate([quads, cap])
    if len(holes):
        centre = dirs[tris].mean(axis=1)
        centre /= np.linalg.norm(centre, axis=1, keepdims=True)
        keep = np.ones(len(tris), bool)
        for h, ang in holes:
            keep &= centre @ np.asarray(h, float) < np.cos(ang)
        tris = tris[keep]
    return radius * dirs, dirs, tris.astype(np.uint32)


def disk(radius: float, z: float = 0.0, n: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Triangle fan of a disk in the plane z, facing +z. Returns vertices and triangle indices."""
    t = np.linspace(0.0, 2 * np.pi, n + 1)[:-1]
    rim = np.column_stack([radius * np.cos(t), radius * np.sin(t), np.full(n, z)])
    verts = np.vstack([[0.0, 0.0, z], rim])
    k = np.arange(n)
    tris = np.column_stack([np.zeros(n, int), 1 + k, 1 + (k + 1) % n])
    return verts, tris.astype(np.uint32)


def ring(centre: np.ndarray, normal: np.ndarray, radius: float, n: int = 32) -> np.ndarray:
    """Closed circle of n+1 points about centre in the plane with the given normal."""
    nrm = np.asarray(normal, float) / np.linalg.norm(normal)
    hint = np.array([0.0, 0.0, 1.0]) if abs(nrm[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(nrm, hint)
    u /= np.linalg.norm(u)
    v = np.cross(nrm, u)
    t = np.linspace(0.0, 2 * np.pi, n + 1)[:, None]
    return np.asarray(centre, float) + radius * (np.cos(t) * u + np.sin(t) * v)


def viridis(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """RGBA uint8 colours on a viridis ramp from lo (purple) to hi (yellow); NaN maps to lo."""
    x = np.nan_to_num(np.asarray(values, float).ravel(), nan=lo)
    s = np.clip((x - lo) / max(hi - lo, 1e-12), 0.0, 1.0) * (len(_VIRIDIS) - 1)
    k = np.minimum(s.astype(int), len(_VIRIDIS) - 2)
    f = (s - k)[:, None]
    rgb = (1 - f) * _VIRIDIS[k] + f * _VIRIDIS[k + 1]
    return np.column_stack([rgb, np.full(len(x), 255.0)]).round().astype(np.uint8)


def rgba(color, alpha: float | None = None) -> np.ndarray:
    """A 0..1 RGB(A) tuple as RGBA uint8, optionally with a new alpha."""
    c = list(color) + [1.0] * (4 - len(color))
    if alpha is not None:
        c[3] = alpha
    return (np.clip(np.asarray(c, float), 0, 1) * 255).round().astype(np.uint8)
