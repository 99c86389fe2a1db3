"""Shared test setup: offscreen rendering, quiet Rerun, spec paths."""

import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("CI", "1")

import pytest  # noqa: E402

SPECS = Path(__file__).resolve().parent.parent / "specs"
TASKS = ["imagecentring", "periscoping", "tracelines"]


@pytest.fixture(params=TASKS)
def task_name(request):
    """Each bundled FAST task by name."""
    return request.param


def spec_file(name: str) -> Path:
    """Path of a bundled spec."""
    return SPECS / f"{name}.yaml"
