"""Read the compiled model's data into the task state: camera pose, target errors, contacts."""

from __future__ import annotations

import hashlib
import math
from functools import lru_cache

import mujoco
import numpy as np

from ..atomic import atomic_write
from ..cache import cache_dir
from ..model.compiler import CompiledTask
from ..spec.geometry import sample_polyline
from ..terms.rewards import cue_potential
from ..terms.state import TaskState
from ..terms.vec import dot, mat_quat, norm

LINE_RESOLUTION = 0.0005  # grid cell of the line-deviation lookup (m)
# Rays see world geoms (group 0) only: avatars (1) do not occlude, the shell (2) cannot occlude a point
# on the inside of a convex dome, and group 3 holds the scope's internal masses around the camera.
RAY_GROUPS = np.array([1, 0, 0, 0, 1, 1], np.uint8)


class Sensor:
    """Fills a TaskState from MjData for the current subtask; cheap enough for every step."""

    def __init__(self, task: CompiledTask, rays: bool):
        self.task, self.rays = task, rays
        self.cam = task.camera
        self.qslice = slice(int(task.qadr[0]), int(task.qadr[0]) + 5)
        assert list(task.qadr) == list(range(self.qslice.start, self.qslice.stop)), "portal joints must be contiguous"
        self.line = task.targets.line
        if self.line is not None:
            self.line_grid = distance_grid(tuple(map(tuple, self.line[:, :2].round(9))), task.spec.scene.radius + 0.03)
        self.geomid = np.zeros(1, np.int32)
        self.ray_points = np.zeros((0, 3))
        self.ray_exclude = task.model.body("scope_shaft").id
        self.cos_half_fov = math.cos(math.radians(0.5 * task.model.cam_fovy[self.cam]))
        self.ray_pnt, self.ray_vec = np.zeros(3), np.zeros(3)
        self.views = None

    def bind(self, data: mujoco.MjData) -> None:
        """Keep views into the data the sensor reads (they stay valid for the data's lifetime)."""
        self.views = (data.cam_xpos[self.cam], data.cam_xmat[self.cam], data.qpos[self.qslice])

    def set_target(self, s: TaskState, k: int, pos, fwd, up, quat) -> None:
        """Point the state at subtask k's avatar and tolerances."""
        t = self.task.targets
        s.subtask = k
        s.target_pos, s.target_fwd = tuple(pos.tolist()), tuple(fwd.tolist())
        s.target_up, s.target_quat = tuple(up.tolist()), tuple(quat.tolist())
        s.tol_centring, s.tol_horizon = float(t.centring[k]), float(t.horizon[k])
        s.dist_lo, s.dist_hi = float(t.dist[k, 0]), float(t.dist[k, 1])
        s.dwell_time = float(t.dwell[k])
        if self.rays:
            self.ray_points = avatar_ray_points(t.size, pos, fwd, up)

    def read(self, s: TaskState, model: mujoco.MjModel, data: mujoco.MjData, first: bool) -> None:
        """Update the state from the data (positions current, as after mj_step1 or mj_forward)."""
        xpos, xmat, qpos = self.views
        pos = tuple(xpos.tolist())
        m = xmat.tolist()
        quat = mat_quat(m)
        q = tuple(qpos.tolist())
        if first:
            s.tip_vel = s.tip_accel = (0.0, 0.0, 0.0)
            s.tip_quat_rate, s.portal_vel = (0.0,) * 4, (0.0,) * 5
        else:
            k = 1.0 / s.dt
            p0, v0, q0 = s.tip_pos, s.tip_vel, s.tip_quat
            if quat[0] * q0[0] + quat[1] * q0[1] + quat[2] * q0[2] + quat[3] * q0[3] < 0:
                q0 = (-q0[0], -q0[1], -q0[2], -q0[3])
            vel = ((pos[0] - p0[0]) * k, (pos[1] - p0[1]) * k, (pos[2] - p0[2]) * k)
            s.tip_accel = ((vel[0] - v0[0]) * k, (vel[1] - v0[1]) * k, (vel[2] - v0[2]) * k)
            s.tip_vel = vel
            s.tip_quat_rate = (
                (quat[0] - q0[0]) * k,
                (quat[1] - q0[1]) * k,
                (quat[2] - q0[2]) * k,
                (quat[3] - q0[3]) * k,
            )
            q1 = s.portal
            s.portal_vel = (
                (q[0] - q1[0]) * k,
                (q[1] - q1[1]) * k,
                (q[2] - q1[2]) * k,
                (q[3] - q1[3]) * k,
                (q[4] - q1[4]) * k,
            )
        s.tip_pos = s.cam_pos = pos
        s.tip_quat, s.portal = quat, q
        s.tip_speed = norm(s.tip_vel)
        s.cam_right = (m[0], m[3], m[6])
        s.cam_up = (m[1], m[4], m[7])
        s.cam_fwd = (-m[2], -m[5], -m[8])
        s.contacts = data.ncon
        if self.line is not None:
            s.line_deviation = self._line_deviation(pos, s.cam_fwd)
        previous = s.potential
        self.errors(s, model, data)
        s.prev_potential = s.potential if first else previous

    def errors(self, s: TaskState, model, data) -> None:
        """Target-dependent quantities: distance, centring, horizon, rays, potential."""
        s.distance, s.centring, s.horizon = view_errors(s, s.target_pos, s.target_up)
        if self.rays:
            s.ray_fraction = self.ray_fraction(model, data, self.ray_points, s.cam_pos, s.cam_fwd)
        s.potential = cue_potential(s)

    def green_on(self, s: TaskState, k: int, pos: tuple, up: tuple) -> bool:
        """Whether the camera of `s` meets subtask k's tolerances for an avatar at `pos` with `up` (the cue's
        geometry alone, as cue_checks reads it for the current one)."""
        t = self.task.targets
        dist, centring, horizon = view_errors(s, pos, up)
        return centring <= t.centring[k] and horizon <= t.horizon[k] and t.dist[k, 0] <= dist <= t.dist[k, 1]

    def line_deviations(self, pos: np.ndarray, fwd: np.ndarray) -> np.ndarray:
        """_line_deviation at many camera positions and forward vectors, (T, 3) each."""
        out = np.full(len(pos), 0.1)
        down = ~(fwd[:, 2] > -1e-3)
        p, f = pos[down], fwd[down]
        k = p[:, 2] / f[:, 2]
        out[down] = self.line_grid.lookup(p[:, 0] - f[:, 0] * k, p[:, 1] - f[:, 1] * k)
        return out

    def _line_deviation(self, pos, fwd) -> float:
        """Distance on the plate from where the optical axis meets it to the nearest point of the line."""
        if fwd[2] > -1e-3:
            return 0.1
        k = pos[2] / fwd[2]
        return self.line_grid(pos[0] - fwd[0] * k, pos[1] - fwd[1] * k)

    def ray_fraction(self, model, data, points: list[tuple], c: tuple, f: tuple) -> float:
        """Share of an avatar's ray points in view of a camera at c looking along f and not occluded (the scene
        placed as the camera sees it)."""
        seen = 0
        pnt, vec = self.ray_pnt, self.ray_vec
        pnt[:] = c
        for p in points:
            d = (p[0] - c[0], p[1] - c[1], p[2] - c[2])
            n = norm(d)
            if dot(d, f) < self.cos_half_fov * n:
                continue
            vec[:] = d
            hit = mujoco.mj_ray(model, data, pnt, vec, RAY_GROUPS, 1, self.ray_exclude, self.geomid)
            if hit < 0 or hit >= 1.0 - 1e-3 / n:  # distance in units of |vec|: beyond the point
                seen += 1
        return seen / len(points)


def view_errors(s: TaskState, pos: tuple, up: tuple) -> tuple[float, float, float]:
    """Distance, centring and horizon error of the camera of `s` on an avatar at `pos` with `up`."""
    p = s.cam_pos
    d = (pos[0] - p[0], pos[1] - p[1], pos[2] - p[2])
    dist = norm(d)
    centring = math.acos(max(-1.0, min(1.0, dot(d, s.cam_fwd) / max(dist, 1e-9))))
    return dist, centring, abs(math.atan2(dot(up, s.cam_right), dot(up, s.cam_up)))


def avatar_ray_points(size: float, pos: np.ndarray, fwd: np.ndarray, up: np.ndarray) -> list[tuple]:
    """The points of an avatar that rays aim at: its centre and four on a ring, just in front of its face."""
    r = 0.8 * size
    x = np.cross(up, fwd)
    angles = np.linspace(0, 2 * math.pi, 4, endpoint=False)
    ring = [pos + r * (math.cos(a) * x + math.sin(a) * up) for a in angles]
    return [tuple(p) for p in (np.array([pos] + ring) + 2e-3 * fwd).tolist()]


class DistanceGrid:
    """Distance to a polyline on the plate on a grid, interpolated bilinearly. The grid is computed once per machine
    and line (0.3 s with scipy's KD-tree, which takes 0.2 s to import) and read from fastrl's cache after."""

    def __init__(self, points: np.ndarray, cell: float = LINE_RESOLUTION, extent: float = 0.2, cap: float = 0.1):
        self.x0, self.cell, self.cap = -extent, cell, cap
        self.n = int(round(2 * extent / cell)) + 1
        self.axis = self.x0 + cell * np.arange(self.n)
        self.values = cached_grid(np.asarray(points, float), self.axis, cell, cap)
        self.grid = self.values.tolist()  # lists: the scalar lookup reads them fastest

    def __call__(self, x: float, y: float) -> float:
        """Interpolated distance (m) at plate point (x, y), capped."""
        u, v = (x - self.x0) / self.cell, (y - self.x0) / self.cell
        if not (0.0 <= u < self.n - 1 and 0.0 <= v < self.n - 1):
            return self.cap
        i, j = int(u), int(v)
        a, b = u - i, v - j
        g0, g1 = self.grid[i], self.grid[i + 1]
        return (1 - a) * ((1 - b) * g0[j] + b * g0[j + 1]) + a * ((1 - b) * g1[j] + b * g1[j + 1])

    def lookup(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The same interpolated distances at many plate points (arrays of x and y)."""
        u, v = (x - self.x0) / self.cell, (y - self.x0) / self.cell
        inside = (0.0 <= u) & (u < self.n - 1) & (0.0 <= v) & (v < self.n - 1)
        u, v = u[inside], v[inside]
        i, j = u.astype(int), v.astype(int)
        a, b, g = u - i, v - j, self.values
        out = np.full(len(x), self.cap)
        out[inside] = (1 - a) * ((1 - b) * g[i, j] + b * g[i, j + 1]) + a * (
            (1 - b) * g[i + 1, j] + b * g[i + 1, j + 1]
        )
        return out


def line_distances(points: np.ndarray, axis: np.ndarray, cell: float, cap: float) -> np.ndarray:
    """The distance from each point of the square grid on `axis` to the nearest point of the line sampled densely,
    capped."""
    from scipy.spatial import cKDTree  # here: only a grid missing from the cache needs it

    gx, gy = np.meshgrid(axis, axis, indexing="ij")
    tree = cKDTree(sample_polyline(points, 0.25 * cell))
    # beyond the cap the query stops early and returns inf, which the cap replaces
    dist, _ = tree.query(np.column_stack([gx.ravel(), gy.ravel()]), distance_upper_bound=cap)
    return np.minimum(dist.reshape(gx.shape), cap)


def cached_grid(points: np.ndarray, axis: np.ndarray, cell: float, cap: float) -> np.ndarray:
    """line_distances, read from fastrl's cache where an earlier process wrote them (else computed and written)."""
    key = hashlib.sha256(b"".join(np.ascontiguousarray(a, float).tobytes() for a in (points, axis, [cell, cap])))
    path = cache_dir() / "line-distance" / f"{key.hexdigest()[:24]}.npy"
    try:
        values = np.load(path)
        if values.shape == (len(axis), len(axis)) and values.dtype == float:
            return values
    except (OSError, ValueError, EOFError):
        pass  # none yet, or unreadable: computed again
    values = line_distances(points, axis, cell, cap)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, lambda f: np.save(f, values))
    except OSError:
        pass  # a cache that cannot be written: the next process computes the grid again
    return values


@lru_cache(maxsize=8)
def distance_grid(points: tuple, extent: float) -> DistanceGrid:
    """The distance grid of a line, shared by every env of the same task."""
    return DistanceGrid(np.array(points), extent=extent)


__all__ = ["Sensor"]
