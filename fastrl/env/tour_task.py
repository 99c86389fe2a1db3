"""The abdomen tour (liver tour): landmarks fixed to the anatomy, visualised in order with the laparoscope."""

from __future__ import annotations

from .task import Task


class TourTask(Task):
    """The scope's cue machine over the tour's landmarks: fixed points of the organs, never moved."""
