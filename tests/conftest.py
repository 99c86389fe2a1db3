"""Shared test setup: offscreen rendering, quiet Rerun, spec paths."""

import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("CI", "1")
# Ray (tests/runner/test_sweep.py) on loopback only: otherwise it resolves 127.0.0.1 to the machine's network address.
os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")

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
