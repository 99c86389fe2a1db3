"""What a trained run writes for others to read: its networks as safetensors, and the motion density beside them."""

from __future__ import annotations

from pathlib import Path

from ...assess.motion import FILE as MOTION_FILE
from ...irl.export import save_networks
from .learner import Learner


def export_networks(folder: Path, learner: Learner) -> None:
    """Policy, value and (learning from demonstrations) reward into `folder`, with the motion density the learned
    reward weighs, where the task observes the camera's velocities."""
    gamma = learner.spec.learning().params().gamma
    save_networks(folder, learner.model, learner.venv, learner.disc, gamma, learner.snapshots, learner.demonstrated)
    if (motion := learner.learned_motion) is not None:
        motion.save(folder / MOTION_FILE)
