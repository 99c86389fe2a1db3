"""Portal kinematics on a compiled task: camera pose from portal coordinates, and the view solver."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from .compiler import CompiledTask


class Kinematics:
    """Forward kinematics of the scope on a scratch MjData (never the live one)."""

    def __init__(self, task: CompiledTask):
        self.task = task
        self.data = mujoco.MjData(task.model)
        self.qadr = task.qadr

    def camera(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Camera position and rotation (columns: right, up, backward) at portal coordinates q."""
        d = self.data
        d.qpos[self.qadr] = q
        d.qpos[self.task.lens_qadr] = -q[4]
        mujoco.mj_kinematics(self.task.model, d)
        mujoco.mj_camlight(self.task.model, d)
        return d.cam_xpos[self.task.camera].copy(), d.cam_xmat[self.task.camera].reshape(3, 3).copy()


def view_residuals(pos, rot, target, fwd_t, up_t, dist_mid, dist_span) -> np.ndarray:
    """Centring (2 angles), horizon (signed angle) and distance error of a camera pose on a target."""
    d = target - pos
    local = rot.T @ d  # x right, y up, z backward
    ahead = -local[2]  # negative when the target is behind: the angles then exceed 90 degrees
    x_img, y_img = up_t @ rot[:, 0], up_t @ rot[:, 1]
    return np.array(
        [
            math.atan2(local[0], ahead),
            math.atan2(local[1], ahead),
            math.atan2(x_img, y_img),
            (np.linalg.norm(d) - dist_mid) / dist_span,
        ]
    )


def solve_view(
    kin: Kinematics,
    k: int,
    q0: np.ndarray,
    target=None,
    pivot_weight: float = 0.02,
    margin: float = 0.008,
    cable_weight: float = 0.005,
    level: bool = True,
) -> tuple[np.ndarray, float]:
    """Portal coordinates that centre, level and hold subtask k's avatar at mid distance, near q0."""
    from scipy.optimize import least_squares  # here: 0.2 s to import, and scoring a file solves nothing

    task = kin.task
    t = task.targets
    pos_t, fwd_t, up_t = target if target is not None else (t.pos[k], t.fwd[k], t.up[k])
    lo, hi = task.ranges[:, 0], task.ranges[:, 1]
    mid, span = float(t.dist[k].mean()), float(t.dist[k, 1] - t.dist[k, 0])
    radius = task.spec.scene.radius
    reg = np.array([pivot_weight, pivot_weight, 0.2, 0.005, cable_weight])

    def residuals(q):
        pos, rot = kin.camera(q)
        r = view_residuals(pos, rot, pos_t, fwd_t, up_t, mid, span)
        r[:3] /= np.array([t.centring[k], t.centring[k], t.horizon[k]]) * 0.5
        if not level:  # any horizon will do: no roll or cable turn for it
            r[2] = 0.0
        inside = [max(0.0, np.linalg.norm(pos) - (radius - margin)) * 500, max(0.0, margin - pos[2]) * 500]
        return np.concatenate([r, inside, reg * (q - q0)])

    best = None
    retracted = lo[2] + 0.15 * (hi[2] - lo[2])  # a target behind the camera is ahead again once retracted
    starts = [(dc, None) for dc in (0.0, math.pi / 2, -math.pi / 2, math.pi)] + [(0.0, retracted), (math.pi, retracted)]
    for dcable, insertion in starts:
        start = np.clip(q0 + np.array([0, 0, 0, 0, dcable]), lo + 1e-6, hi - 1e-6)
        start[4] = (start[4] + math.pi) % (2 * math.pi) - math.pi
        if insertion is not None:
            start[2] = insertion
        sol = least_squares(residuals, start, bounds=(lo, hi), xtol=1e-8, ftol=1e-8, max_nfev=200)
        if best is None or sol.cost < best.cost:
            best = sol
        if best.cost < 0.05:
            break
    return best.x, float(best.cost)
