"""Pure reward and observation terms over the task state, registered by name."""

from . import observations, rewards, tools  # noqa: F401  (registers the terms)
from .registry import OBSERVATION_TERMS, REWARD_FEATURES, Term
from .rewards import cue_potential, tolerance
from .state import InstrumentState, TaskState

__all__ = [
    "OBSERVATION_TERMS",
    "REWARD_FEATURES",
    "InstrumentState",
    "Term",
    "TaskState",
    "cue_potential",
    "tolerance",
]
