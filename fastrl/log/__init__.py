"""Rerun recording of a run: scene, evaluation episodes, training curves, summary, layout."""

from .recording import RunRecorder

__all__ = ["RunRecorder"]
