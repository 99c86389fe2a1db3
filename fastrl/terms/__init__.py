"""Reward, observation, reset and termination terms over the task state, registered by name."""

from . import observations, rewards  # noqa: I001, F401  (registers the scope's terms, then the instruments')
from . import instruments  # noqa: F401
from .episode import EpisodeStart
from .registry import OBSERVATION_TERMS, RESET_TERMS, REWARD_FEATURES, TERMINATION_TERMS, Term
from .rewards import cue_potential, tolerance
from .state import InstrumentState, TaskState

__all__ = [
    "OBSERVATION_TERMS",
    "RESET_TERMS",
    "REWARD_FEATURES",
    "TERMINATION_TERMS",
    "EpisodeStart",
    "InstrumentState",
    "Term",
    "TaskState",
    "cue_potential",
    "tolerance",
]
