"""Tiny 3-vector helpers on tuples of floats: far cheaper than numpy for single vectors."""

from __future__ import annotations

import math

Vec = tuple[float, float, float]


def dot(a, b) -> float:
    """a . b"""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b) -> Vec:
    """a x b"""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def sub(a, b) -> Vec:
    """a - b"""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def norm(a) -> float:
    """|a|"""
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def mat_quat(m) -> tuple[float, float, float, float]:
    """Row-major 3x3 rotation (9 floats) to a unit quaternion (w, x, y, z) with w >= 0."""
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = m
    t = m00 + m11 + m22
    if t > 0:
        r = math.sqrt(t + 1.0) * 2
        q = (0.25 * r, (m21 - m12) / r, (m02 - m20) / r, (m10 - m01) / r)
    elif m00 > m11 and m00 > m22:
        r = math.sqrt(1.0 + m00 - m11 - m22) * 2
        q = ((m21 - m12) / r, 0.25 * r, (m01 + m10) / r, (m02 + m20) / r)
    elif m11 > m22:
        r = math.sqrt(1.0 + m11 - m00 - m22) * 2
        q = ((m02 - m20) / r, (m01 + m10) / r, 0.25 * r, (m12 + m21) / r)
    else:
        r = math.sqrt(1.0 + m22 - m00 - m11) * 2
        q = ((m10 - m01) / r, (m02 + m20) / r, (m12 + m21) / r, 0.25 * r)
    return q if q[0] >= 0 else (-q[0], -q[1], -q[2], -q[3])
