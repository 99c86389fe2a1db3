"""Episode records and the trajectory contract."""

from .episode import EpisodeRecord
from .trajectory import COORDINATES, SOURCES, Trajectory, TrajectoryError, load_trajectories

__all__ = ["COORDINATES", "SOURCES", "EpisodeRecord", "Trajectory", "TrajectoryError", "load_trajectories"]
