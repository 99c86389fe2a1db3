"""Skill assessment: score trajectories by replay, rank subjects, draw where they went wrong."""

from .ranking import rank_correlations
from .scoring import Scorer, TrajectoryScores

__all__ = ["Scorer", "TrajectoryScores", "rank_correlations"]
