"""Recordings made ready to learn from: read file by file, put on the control grid, actions recovered where missing."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .inverse import ActionRecovery, on_control_grid, to_control_rate
from .trajectory import VIDEO_ONLY, Trajectory, TrajectoryError, load_files

METHOD = {
    "discrete": "exact search over every discrete action",
    "rates": "least squares through the simulator's step, clipped to the action box",
    "continuous": "least squares through the simulator's step, clipped to the action box",
}


def action_problem(traj: Trajectory, mode: str) -> str | None:
    """Why a trajectory's actions cannot be learned from in this action mode, or None."""
    if traj.actions is None:
        return "has no actions"
    a = np.asarray(traj.actions)
    if mode == "discrete" and a.ndim != 1:
        return f"has continuous actions {a.shape}, the spec's actions are discrete"
    width = {"continuous": 7, "rates": 5}.get(mode)
    if width is not None and (a.ndim != 2 or a.shape[1] != width):
        return f"has actions of shape {a.shape}, the spec's actions are {mode} ({width} per step)"
    return None


def load_recordings(paths, ranges: np.ndarray | None = None) -> tuple[list[tuple[Path, Trajectory]], list[str]]:
    """(file, trajectory) for every readable .npz under the given files or folders (coordinates checked against
    joint ranges (5, 2) if given); the rest as messages naming them."""
    files = []
    for p in map(Path, paths):
        files += sorted(p.glob("*.npz")) if p.is_dir() else [p]
    return load_files(files, ranges)


@dataclass
class Prepared:
    """Trajectories with actions in the spec's mode, and what was done to get them."""

    trajectories: list[Trajectory] = field(default_factory=list)
    resampled: int = 0
    recovered: int = 0
    residual: list[float] = field(default_factory=list)  # per recovered step: weighted pose error, deg ~ mm
    errors: list[str] = field(default_factory=list)

    def notes(self, mode: str) -> list[str]:
        """One line per thing done to the recordings."""
        out = []
        if self.resampled:
            out.append(f"resampled {self.resampled} recordings to the control rate (linear, roll and cable unwrapped)")
        if self.recovered:
            r = np.asarray(self.residual)
            out.append(
                f"recovered the actions of {self.recovered} of {len(self.trajectories)} demonstrations from their "
                f"states ({METHOD[mode]}); next-pose residual mean {r.mean():.3g}, max {r.max():.3g} (deg ~ mm)"
            )
        return out


def with_actions(env, named: list[tuple[str, Trajectory]]) -> Prepared:
    """Each (name, trajectory) on the env's control grid, with its actions recovered from the states where it has
    none or has actions of another mode; a trajectory that cannot be used becomes a message naming it."""
    u = env.unwrapped
    hz, mode = u.task_spec.episode.control_hz, u.task_spec.actions.mode
    recovery = None
    out = Prepared()
    for name, traj in named:
        try:
            if traj.portal is None:
                raise TrajectoryError(VIDEO_ONLY)
            if not on_control_grid(traj, hz):
                traj = to_control_rate(traj, hz)
                out.resampled += 1
            if action_problem(traj, mode) is not None:
                recovery = recovery or ActionRecovery(u)
                rec = recovery.recover(traj)
                traj = Trajectory(
                    traj.time,
                    traj.portal,
                    {**traj.meta, "actions": "recovered"},
                    rec.actions,
                    traj.instruments,
                    traj.bodies,
                )
                out.recovered += 1
                out.residual += rec.residual.tolist()
        except (TrajectoryError, ValueError) as e:
            out.errors.append(f"{name}: {e}")
            continue
        out.trajectories.append(traj)
    return out
