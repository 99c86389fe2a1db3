"""One episode as arrays: what evaluation measures and what the recording shows."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class EpisodeRecord:
    """Per-step arrays of one episode (T steps after the reset state at index 0)."""

    seed: int
    time: np.ndarray  # (T+1,) s
    portal: np.ndarray  # (T+1, 5) [pitch, yaw, insertion, roll, cable]
    tip_pos: np.ndarray  # (T+1, 3) camera / tip position
    tip_quat: np.ndarray  # (T+1, 4) camera orientation, wxyz, MuJoCo camera convention (looks along -Z)
    shaft_end: np.ndarray  # (T+1, 3) the shaft's outer end (the tip is the other end)
    reward: np.ndarray  # (T+1,) reward received on arriving at each state (0 at the reset)
    features: dict[str, np.ndarray]  # name -> (T+1,)
    subtask: np.ndarray  # (T+1,) subtasks completed
    green: np.ndarray  # (T+1,) bool: all cues holding for the current avatar
    contacts: np.ndarray  # (T+1,) number of tip contacts
    actions: np.ndarray | None = None  # (T, ...) actions taken
    images: dict[int, np.ndarray] = field(default_factory=dict)  # step -> endoscope image (H, W, 3) uint8
    frames: dict[int, np.ndarray] = field(default_factory=dict)  # step -> the policy's frames side by side, uint8
    subtasks_total: int = 0
    success: bool = False
    tools: np.ndarray | None = None  # (T+1, n, 2, 3) each instrument's tip and shaft end, if the task has any
    bodies: np.ndarray | None = None  # (T+1, k, 3) LooseBodies' free bodies' centres, if the task has any

    @property
    def steps(self) -> int:
        """Number of environment steps."""
        return len(self.time) - 1

    @property
    def path_length(self) -> float:
        """Distance travelled by the tip (m)."""
        return float(np.linalg.norm(np.diff(self.tip_pos, axis=0), axis=1).sum())

    def summary(self) -> dict:
        """Headline figures of the episode."""
        return {
            "seed": self.seed,
            "success": bool(self.success),
            "subtasks": int(self.subtask[-1]),
            "subtasks_total": int(self.subtasks_total),
            "return": float(self.reward.sum()),
            "episode_time": float(self.time[-1]),
            "steps": self.steps,
            "path_length": self.path_length,
            "contacts": int((self.contacts > 0).sum()),
            "features": {k: float(v.sum()) for k, v in self.features.items()},
        }
