"""Episode and trajectory data."""

from .episode import EpisodeRecord

__all__ = ["EpisodeRecord"]
