"""`fastrl run` and `fastrl irl`: start or continue a run or an experiment, its spec compiled once."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rich.console import Console

from ..model.compiler import CompiledTask
from ..model.loaded import load_task
from .runfiles import read_meta


@dataclass(frozen=True)
class Training:
    """What to train: a spec (compiled) with its overrides, or a run directory to continue; a run or an experiment."""

    spec_path: Path | None
    overrides: tuple[str, ...]
    resume: Path | None
    task: CompiledTask | None
    experiment: bool


def is_experiment(run: Path) -> bool:
    """Whether a run directory holds an experiment (its experiment.json, or meta.json kind)."""
    return (run / "experiment.json").exists() or (
        (run / "meta.json").exists() and read_meta(run).get("kind") == "experiment"
    )


def plan_training(spec_path: Path | None, overrides=(), resume: Path | None = None) -> Training:
    """A new run or experiment of a spec (validated and compiled: SpecError), or the one in `resume` to continue."""
    if resume is not None:
        return Training(None, (), Path(resume), None, is_experiment(Path(resume)))
    task = load_task(spec_path, overrides)
    return Training(Path(spec_path), tuple(overrides), None, task, task.spec.experiment.enabled)


def train(plan: Training, runs: Path, console: Console, progress: bool = True, timesteps: int | None = None) -> Path:
    """Start or continue the planned run or experiment; return its directory."""
    if plan.experiment:
        from .experiment import run_experiment, start_experiment

        if plan.resume is not None:
            return run_experiment(plan.resume, console, progress)
        return start_experiment(plan.spec_path, list(plan.overrides), runs, console, progress, task=plan.task)
    from .run import resume_run, start_run

    if plan.resume is not None:
        return resume_run(plan.resume, console, progress, timesteps)
    return start_run(plan.spec_path, list(plan.overrides), runs, console, progress, task=plan.task)
