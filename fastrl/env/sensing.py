"""Read the compiled model's data into the task state: camera pose, target errors, contacts."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..model.compiler import CompiledTask
from ..spec.geometry import sample_polyline
from ..terms.rewards import cue_potential
from ..terms.state import TaskState
from ..terms.vec import dot, mat_quat, norm

LINE_RESOLUTION = 0.0005  # the line is sampled every 0.5 mm for the deviation (error <= 0.25 mm)
RAY_GROUPS = np.array([1, 0, 1, 1, 1, 1], np.uint8)  # avatars (group 1) do not occlude


class Sensor:
    """Fills a TaskState from MjData for the current subtask; cheap enough for every step."""

    def __init__(self, task: CompiledTask, rays: bool):
        self.task, self.rays = task, rays
        self.cam = task.camera
        self.qslice = slice(int(task.qadr[0]), int(task.qadr[0]) + 5)
        assert list(task.qadr) == list(range(self.qslice.start, self.qslice.stop)), "portal joints must be contiguous"
        self.line = task.targets.line
        if self.line is not None:
            self.line_points = sample_polyline(self.line[:, :2], LINE_RESOLUTION)
        self.geomid = np.zeros(1, np.int32)
        self.ray_points = np.zeros((0, 3))
        self.ray_exclude = task.model.body("scope_shaft").id
        self.half_fov = math.radians(0.5 * task.model.cam_fovy[self.cam])

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
            r = 0.8 * t.size
            x = np.cross(up, fwd)
            ring = [pos + r * (math.cos(a) * x + math.sin(a) * up) for a in np.linspace(0, 2 * math.pi, 8, endpoint=False)]
            self.ray_points = np.array([pos] + ring) + 2e-3 * fwd

    def read(self, s: TaskState, model: mujoco.MjModel, data: mujoco.MjData, first: bool) -> None:
        """Update the state from the data (positions current, as after mj_step1 or mj_forward)."""
        pos = tuple(data.cam_xpos[self.cam].tolist())
        m = data.cam_xmat[self.cam].tolist()
        quat = mat_quat(m)
        q = tuple(data.qpos[self.qslice].tolist())
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
            s.tip_quat_rate = tuple((a - b) * k for a, b in zip(quat, q0))
            s.portal_vel = tuple((a - b) * k for a, b in zip(q, s.portal))
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
        p, t = s.cam_pos, s.target_pos
        d = (t[0] - p[0], t[1] - p[1], t[2] - p[2])
        dist = norm(d)
        s.distance = dist
        s.centring = math.acos(max(-1.0, min(1.0, dot(d, s.cam_fwd) / max(dist, 1e-9))))
        u = s.target_up
        s.horizon = abs(math.atan2(dot(u, s.cam_right), dot(u, s.cam_up)))
        if self.rays:
            s.ray_fraction = self._ray_fraction(model, data, s)
        s.potential = cue_potential(s)

    def _line_deviation(self, pos, fwd) -> float:
        """Distance on the plate from where the optical axis meets it to the nearest point of the line."""
        if fwd[2] > -1e-3:
            return 0.1
        k = pos[2] / fwd[2]
        e = self.line_points - (pos[0] - fwd[0] * k, pos[1] - fwd[1] * k)
        return math.sqrt(min(0.01, float(np.einsum("ij,ij->i", e, e).min())))

    def _ray_fraction(self, model, data, s: TaskState) -> float:
        """Share of avatar sample points in view and not occluded from the camera."""
        seen = 0
        cam = np.array(s.cam_pos)
        for p in self.ray_points:
            d = p - cam
            n = math.sqrt(d @ d)
            if math.acos(max(-1.0, min(1.0, dot(d, s.cam_fwd) / n))) > self.half_fov:
                continue
            hit = mujoco.mj_ray(model, data, cam, d / n, RAY_GROUPS, 1, self.ray_exclude, self.geomid)
            if hit < 0 or hit >= n - 1e-3:
                seen += 1
        return seen / len(self.ray_points)


__all__ = ["Sensor"]
