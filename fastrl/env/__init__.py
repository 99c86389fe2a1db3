"""Gymnasium environments over compiled FAST tasks."""

from .actions import DISCRETE_MEANINGS
from .fast_env import FastEnv

__all__ = ["DISCRETE_MEANINGS", "FastEnv"]
