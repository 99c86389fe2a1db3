"""fastrl: FAST arthroscopy tasks as YAML specs compiled to MuJoCo and Gymnasium environments."""

from __future__ import annotations

import os
import sys

if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")  # offscreen rendering on headless machines (before mujoco loads)
# numpy's matrix products are small here (the exported networks, evaluated in numpy by `fastrl score`): OpenBLAS's
# threads cost more than they save, twice so beside a second process on the other core (before numpy loads)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
if "numpy" in sys.modules and os.environ["OPENBLAS_NUM_THREADS"].isdigit():
    # numpy loaded first (a script, pytest, a Ray worker): the variable came too late. On some CPUs (an AMD EPYC of
    # family 25, 2026-12-07) the products' last bits also depend on the threads, so networks scored differently by
    # process; every process that imports fastrl now has the same BLAS threads
    from threadpoolctl import threadpool_limits

    threadpool_limits(int(os.environ["OPENBLAS_NUM_THREADS"]), user_api="blas")

import gymnasium  # noqa: E402

from .about import DISTRIBUTION, VERSION  # noqa: E402,F401 - public: the name on PyPI, the version
from .bundled import SPECS_DIR, spec_path  # noqa: E402,F401 - public: the bundled specs as package data

__version__ = VERSION

TASK_IDS = {
    "ImageCentring": "imagecentring",
    "Periscoping": "periscoping",
    "TraceLines": "tracelines",
    "LiverTour": "liver_tour",
    "Triangulation": "triangulation",
    "LooseBodies": "loose_bodies",
}


def make(
    spec, *, render_mode: str | None = None, width: int = 128, height: int = 128, overrides: list[str] = (), **sections
):
    """Build a FastEnv from a spec path, bundled spec name, TaskSpec or its dict; sections override spec fields."""
    from .env import FastEnv
    from .spec import TaskSpec, apply_overrides, load_spec

    if isinstance(spec, TaskSpec | dict):  # a dict: a resolved spec as plain data (a Minari dataset's env_spec)
        task_spec = spec if isinstance(spec, TaskSpec) else TaskSpec.model_validate(spec)
        if overrides or sections:
            data = apply_overrides(task_spec.model_dump(), list(overrides))
            task_spec = TaskSpec.model_validate(_merge(data, sections))
    else:
        task_spec = load_spec(spec, overrides)
        if sections:
            task_spec = TaskSpec.model_validate(_merge(task_spec.model_dump(), sections))
    return FastEnv(task_spec, render_mode=render_mode, width=width, height=height)


def _merge(base: dict, extra: dict) -> dict:
    """Deep-merge extra into a copy of base."""
    out = dict(base)
    for key, value in extra.items():
        out[key] = _merge(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


for _id, _name in TASK_IDS.items():
    if f"fastrl/{_id}-v0" not in gymnasium.registry:
        gymnasium.register(f"fastrl/{_id}-v0", entry_point="fastrl:make", kwargs={"spec": _name})
