"""Assistance for a trainee: path suggestions from a trained policy, and a value colour cue."""

from .cue import ValueCue, cue_colour
from .project import draw_path, project_points
from .suggest import Suggester, Suggestion

__all__ = ["Suggester", "Suggestion", "ValueCue", "cue_colour", "draw_path", "project_points"]
