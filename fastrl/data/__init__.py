"""Episode records and the trajectory contract."""

from .episode import EpisodeRecord
from .trajectory import COORDINATES, SOURCES, Trajectory, TrajectoryError

__all__ = ["COORDINATES", "SOURCES", "EpisodeRecord", "Trajectory", "TrajectoryError"]
