"""Gymnasium environments over compiled FAST tasks: a thin FastEnv over one Task per task family."""

from .actions import DISCRETE_MEANINGS
from .fast_env import FastEnv
from .task import Task

__all__ = ["DISCRETE_MEANINGS", "FastEnv", "Task"]
