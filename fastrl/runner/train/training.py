"""`fastrl run` and `fastrl irl`: start or continue a run or a study, its spec compiled once."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rich.console import Console

from ...model.compiler import CompiledTask
from ...model.loaded import load_task
from ..runs.runfiles import STUDY_KIND, STUDY_RESULT, read_meta
from .beside import Beside


@dataclass(frozen=True)
class Training:
    """What to train: a spec (compiled) with its overrides, or a run directory to continue; a run or a study."""

    spec_path: Path | None
    overrides: tuple[str, ...]
    resume: Path | None
    task: CompiledTask | None
    study: bool


def is_study(run: Path) -> bool:
    """Whether a run directory holds a study (its Table 3 file, or meta.json kind)."""
    return (run / STUDY_RESULT).exists() or ((run / "meta.json").exists() and read_meta(run).get("kind") == STUDY_KIND)


def plan_training(spec_path: Path | None, overrides=(), resume: Path | None = None) -> Training:
    """A new run or study of a spec (validated and compiled: SpecError), or the one in `resume` to continue."""
    if resume is not None:
        return Training(None, (), Path(resume), None, is_study(Path(resume)))
    task = load_task(spec_path, overrides)
    return Training(Path(spec_path), tuple(overrides), None, task, task.spec.study.enabled)


def expert_started(plan: Training) -> Beside | None:
    """A new run's scripted-expert evaluation, recalled or started now at the lowest priority: before torch and
    Rerun import (2 s of a free CPU on a spec's first run). None for a resume, a study or a spec without it."""
    if plan.task is None or plan.study:
        return None
    from .expert_eval import expert_beside  # here: planning a resume or a study needs no expert

    return expert_beside(plan.task.spec, idle=True)


def train(
    plan: Training,
    runs: Path,
    console: Console,
    progress: bool = True,
    timesteps: int | None = None,
    *,
    expert: Beside | None = None,
) -> Path:
    """Start or continue the planned run or study; return its directory. `expert`: a new run's expert_started."""
    if plan.study:
        from ..study import run_study, start_study

        if plan.resume is not None:
            return run_study(plan.resume, console, progress)
        return start_study(plan.spec_path, list(plan.overrides), runs, console, progress, task=plan.task)
    from .run import resume_run, start_run

    if plan.resume is not None:
        return resume_run(plan.resume, console, progress, timesteps)
    return start_run(plan.spec_path, list(plan.overrides), runs, console, progress, task=plan.task, expert=expert)
