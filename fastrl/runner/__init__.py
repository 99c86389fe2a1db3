"""Run stages: run directory, training with checkpoints, evaluation, recording."""

from importlib import import_module

_FROM = {
    "EvaluationInterrupted": ".stops",
    "RunInterrupted": ".stops",
    "RunOutOfSpace": ".stops",
    "evaluate_expert": ".evaluation",
    "evaluate_saved": ".evaluation",
    "resume_run": ".run",
    "start_run": ".run",
}
__all__ = sorted(_FROM)


def __getattr__(name: str):
    """Import the training stack on first use: `fastrl score` needs none of it."""
    if name in _FROM:
        return getattr(import_module(_FROM[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
