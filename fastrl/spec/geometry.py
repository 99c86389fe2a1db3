"""Pure geometry of the dome scene: where portals and avatars are (numpy only, no MuJoCo)."""

from __future__ import annotations

import math

import numpy as np

from ..terms.vec import mat_quat


def sphere_point(radius: float, azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """Point on a sphere about the origin from azimuth and elevation in degrees."""
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    return radius * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


def frame_from_z(z: np.ndarray, x_hint: np.ndarray | None = None) -> np.ndarray:
    """Right-handed rotation matrix whose columns are x, y, z with z given and x near x_hint."""
    z = z / np.linalg.norm(z)
    hint = np.array([0.0, 0.0, 1.0]) if x_hint is None else x_hint
    if abs(hint @ z) > 0.95:
        hint = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = hint - (hint @ z) * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def mat_to_quat(m: np.ndarray) -> np.ndarray:
    """Rotation matrix to a unit quaternion (w, x, y, z) with w >= 0."""
    q = np.array(mat_quat(np.asarray(m, float).ravel().tolist()))
    return q / np.linalg.norm(q)


def portal_frame(radius: float, azimuth_deg: float, elevation_deg: float, aim) -> tuple:
    """Portal point and rotation: z from the portal to the aim point (shaft at rest), y as near world up as can be."""
    p = sphere_point(radius, azimuth_deg, elevation_deg)
    z = np.asarray(aim, float) - p
    z /= np.linalg.norm(z)
    up = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.95 else np.array([1.0, 0.0, 0.0])
    y = up - (up @ z) * z
    y /= np.linalg.norm(y)
    return p, np.column_stack([np.cross(y, z), y, z])


def avatar_pose(radius: float, surface: str, at, heading_deg: float, lift: float = 0.0005) -> tuple:
    """Avatar position, forward (facing) vector and up vector on the plate or the dome's inner surface."""
    h = math.radians(heading_deg)
    if surface == "plate":
        pos = np.array([at[0], at[1], lift])
        fwd = np.array([0.0, 0.0, 1.0])
        up = np.array([math.cos(h), math.sin(h), 0.0])
    else:
        az, el = math.radians(at[0]), math.radians(at[1])
        pos = sphere_point(radius - lift, at[0], at[1])
        fwd = -pos / np.linalg.norm(pos)
        e_el = np.array([-math.sin(el) * math.cos(az), -math.sin(el) * math.sin(az), math.cos(el)])
        e_az = np.array([-math.sin(az), math.cos(az), 0.0])
        up = math.cos(h) * e_el + math.sin(h) * e_az
    return pos, fwd, up


def avatar_rotation(fwd: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Rotation matrix of an avatar: z = forward (facing), y = up."""
    x = np.cross(up, fwd)
    return np.column_stack([x / np.linalg.norm(x), up, fwd])


def sample_polyline(points: np.ndarray, spacing: float) -> np.ndarray:
    """Points every `spacing` metres along a polyline, ends included."""
    seg = np.diff(points, axis=0)
    lengths = np.linalg.norm(seg, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(lengths)])
    n = max(2, int(round(cum[-1] / spacing)) + 1)
    s = np.linspace(0.0, cum[-1], n)
    return np.column_stack([np.interp(s, cum, points[:, k]) for k in range(points.shape[1])])


def catmull_rom(points: np.ndarray, per_segment: int = 16) -> np.ndarray:
    """Dense Catmull-Rom spline through the control points."""
    p = np.vstack([2 * points[0] - points[1], points, 2 * points[-1] - points[-2]])
    t = np.linspace(0.0, 1.0, per_segment, endpoint=False)[:, None]
    out = []
    for i in range(1, len(p) - 2):
        p0, p1, p2, p3 = p[i - 1], p[i], p[i + 1], p[i + 2]
        out.append(
            0.5
            * (2 * p1 + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t**2 + (-p0 + 3 * p1 - 3 * p2 + p3) * t**3)
        )
    out.append(points[-1:])
    return np.vstack(out)
