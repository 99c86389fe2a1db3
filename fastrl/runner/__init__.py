"""Run stages: run directory, training with checkpoints, evaluation, recording."""

from .run import EvaluationInterrupted, RunInterrupted, evaluate_expert, evaluate_saved, resume_run, start_run

__all__ = ["EvaluationInterrupted", "RunInterrupted", "evaluate_expert", "evaluate_saved", "resume_run", "start_run"]
