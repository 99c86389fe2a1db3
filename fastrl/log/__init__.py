"""Rerun recording of a run: scene, evaluation episodes, training curves, summary, layout."""

from importlib import import_module

__all__ = ["RunRecorder"]


def __getattr__(name: str):
    """Import the run recorder on first use: an assessment recording needs none of it."""
    if name == "RunRecorder":
        return import_module(".recording", __name__).RunRecorder
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
