"""Run stages: run directory, training with checkpoints, evaluation, recording."""

from .run import evaluate_expert, evaluate_saved, resume_run, start_run
from .stops import EvaluationInterrupted, RunInterrupted, RunOutOfSpace

__all__ = [
    "EvaluationInterrupted",
    "RunInterrupted",
    "RunOutOfSpace",
    "evaluate_expert",
    "evaluate_saved",
    "resume_run",
    "start_run",
]
