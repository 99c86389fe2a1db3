"""The applications: train and resume (train/), sweeps (sweep/), scoring (score/), the assess protocol, the Table 3
study; run folders, their files and stops (runs/)."""

from importlib import import_module

_FROM = {
    "EvaluationInterrupted": ".runs.stops",
    "RunInterrupted": ".runs.stops",
    "RunOutOfSpace": ".runs.stops",
    "evaluate_expert": ".train.evaluation",
    "evaluate_saved": ".train.evaluation",
    "resume_run": ".train.run",
    "start_run": ".train.run",
}
__all__ = sorted(_FROM)


def __getattr__(name: str):
    """Import the training stack on first use: `fastrl score` needs none of it."""
    if name in _FROM:
        return getattr(import_module(_FROM[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
