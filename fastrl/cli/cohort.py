"""Synthetic trainee cohorts (`fastrl cohort`)."""

from __future__ import annotations

from . import app  # noqa: F401  (commands register on the shared app)
