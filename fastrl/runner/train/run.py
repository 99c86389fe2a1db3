"""The stages of one run: prepare the run directory, train, checkpoint, evaluate, record."""

from __future__ import annotations

import json
import time
from contextlib import ExitStack
from pathlib import Path

import numpy as np
from rich.console import Console

from ...agents.sb3 import load_checkpoint, policy_function, save_checkpoint
from ...atomic import DiskFull, is_disk_full, write_json, write_text
from ...forked import deferred
from ...log import RunRecorder
from ...log.recording import recording_problem, repair_recording
from ...model.compiler import CompiledTask, compile_task
from ...spec import load_spec
from ...spec.models import TaskSpec
from ..runs.rundir import clean_leftovers, latest_checkpoint, new_run_dir, update_meta, write_meta, write_spec
from ..runs.runfiles import read_meta, read_metrics, read_run_spec, read_state, require
from ..runs.stops import (
    EvaluationInterrupted,
    RunInterrupted,
    RunOutOfSpace,
    check_space,
    shielded,
    signal_name,
    space_to_resume,
    stop_on_sigterm,
)
from .beside import Beside
from .evaluation import evaluate_run, expert_beside
from .learner import build_learner
from .monitoring import training_monitor
from .networks import export_networks
from .warm import warm_start_run

__all__ = ["EvaluationInterrupted", "RunInterrupted", "RunOutOfSpace", "learn_into", "resume_run", "start_run"]


def start_run(
    spec_path,
    overrides=(),
    root="runs",
    console: Console | None = None,
    progress: bool = True,
    into: Path | None = None,
    task: CompiledTask | None = None,
    expert: Beside | None = None,
) -> Path:
    """Train, evaluate and record a new run of a spec file (in `into` if given); return its directory.

    `task`: the spec file with these overrides, compiled already (so it is not compiled again); `expert`: the
    scripted expert's evaluation of this spec, started already (expert_beside)."""
    if task is None:
        task = compile_task(load_spec(spec_path, overrides))
    spec = task.spec
    if into is not None:
        Path(into).mkdir(parents=True, exist_ok=False)
    run = Path(into) if into is not None else new_run_dir(Path(root), spec)
    write_spec(run, spec, task.xml)
    write_meta(run, spec, str(spec_path), {"status": "training", "overrides": list(overrides)})
    with stop_on_sigterm():
        return _train_and_evaluate(run, spec, task, None, console or Console(), progress, expert=expert)


def resume_run(
    run: Path,
    console: Console | None = None,
    progress: bool = True,
    timesteps: int | None = None,
    workers: int | None = None,
) -> Path:
    """Continue a run from its newest whole checkpoint (naming damaged ones) to its budget (`timesteps`: a new one),
    on `workers` processes if given (the split never changes results); evaluate and record.

    A damaged spec.yaml or meta.json raises RunFileError before anything is written."""
    run = Path(run)
    console = console or Console()
    changed = [f"train.timesteps={timesteps}"] * bool(timesteps) + [f"train.workers={workers}"] * bool(workers)
    spec = read_run_spec(run, changed)
    for problem in require(run, {"spec.yaml", "meta.json"}):
        if problem.path.parent.name == "checkpoints":
            continue  # named below, as resume passes over it
        then = (
            "resuming keeps it aside and rewrites it"
            if problem.path.name == "recording.rrd"
            else "resuming rewrites it"
        )
        console.print(f"note: {problem.path}: {problem.fault}; {then}", markup=False, highlight=False)
    task = compile_task(spec)
    if changed:
        write_spec(run, spec, task.xml)
    clean_leftovers(run)
    skipped: list[str] = []
    ckpt = latest_checkpoint(run, skipped)
    for message in skipped:
        console.print(f"skipped damaged checkpoint {message}", markup=False, highlight=False)
    if ckpt is None:
        console.print(f"{run} has no whole checkpoint: training starts again from 0 timesteps", markup=False)
    with stop_on_sigterm():
        return _train_and_evaluate(run, spec, task, ckpt, console, progress, resuming=True)


def learn_into(
    spec_path, overrides, into: Path, *, console: Console, progress: bool = True, workers: int | None = None
) -> Path:
    """The run in `into`: kept if done, resumed from its checkpoint if begun, else started there."""
    more = [f"train.workers={workers}"] if workers else []
    if not into.exists():
        return start_run(spec_path, [*overrides, *more], console=console, progress=progress, into=into)
    if read_meta(into).get("status") == "done":
        return into
    return resume_run(into, console=console, progress=progress, workers=workers)


def _open_recorder(run: Path, spec: TaskSpec, task: CompiledTask, resumed_at: int | None) -> RunRecorder:
    """The run's recording; resuming, the old one is kept aside (repaired) and the curves up to it re-logged."""
    path = run / "recording.rrd"
    if resumed_at is not None and path.exists():
        k = len(list(run.glob("recording.part*.rrd"))) + 1
        part = path.rename(run / f"recording.part{k}.rrd")
        repair_recording(part)
    recorder = RunRecorder(path, recording_id=run.name, run_name=f"{spec.name} {run.name}")
    recorder.log_scene(task)
    n = min(spec.evaluate.record_episodes, spec.evaluate.episodes)
    pixels = spec.observation.image is not None
    warm = spec.train.warm_start is not None
    recorder.send_blueprint(n, spec.irl.enabled, curves=spec.irl.algorithm != "bc", pixels=pixels, warm=warm)
    if resumed_at is not None:
        history = metrics_until(run / "metrics.jsonl", resumed_at)
        if history:
            keys = sorted({k for row in history for k in row} - {"timesteps"})
            recorder.log_training_columns(
                np.array([r["timesteps"] for r in history]),
                {k: np.array([r.get(k, np.nan) for r in history], float) for k in keys},
            )
    return recorder


def metrics_until(path: Path, timesteps: int) -> list[dict]:
    """metrics.jsonl cut back to the rows up to `timesteps` (torn lines dropped), as a resume redoes the rest."""
    if not path.exists():
        return []
    rows = [row for row in read_metrics(path.parent) if row["timesteps"] <= timesteps]
    write_text(path, "".join(json.dumps(r) + "\n" for r in rows))
    return rows


def _train_and_evaluate(
    run: Path,
    spec: TaskSpec,
    task: CompiledTask,
    ckpt: Path | None,
    console: Console,
    progress: bool,
    resuming: bool = False,
    expert: Beside | None = None,
) -> Path:
    """Train (from a checkpoint if given), save, evaluate agent and expert, write eval.json and the recording. The
    expert's evaluation starts first (unless `expert` started it already), beside training at the lowest priority:
    on the CPU time training leaves."""
    with ExitStack() as jobs:  # the expert's evaluation, once started, is stopped whichever way the run ends
        try:
            with deferred():  # its cancel registered before a stop can land
                expert = expert or expert_beside(spec, idle=True)
                if expert is not None:
                    jobs.callback(_cancel, expert)
            learner = build_learner(spec, run, console, progress)
            before = load_checkpoint(ckpt, learner.model, learner.venv, learner.parts) if ckpt else {}
            recorder = _open_recorder(run, spec, task, int(learner.model.num_timesteps) if resuming else None)
        except KeyboardInterrupt as stop:  # before training: writing demonstrations, repairing the old recording
            with shielded():
                update_meta(run, status="interrupted")
            done = read_state(ckpt)["timesteps"] if ckpt else 0
            raise RunInterrupted(run, done, signal_name(stop)) from None
        except OSError as e:
            if not is_disk_full(e):
                raise
            full = e if isinstance(e, DiskFull) else DiskFull(Path(e.filename or run))
            rrd = run / "recording.rrd"
            whole = not rrd.exists() or recording_problem(rrd) is None
            raise RunOutOfSpace(run, full, space_to_resume(run), whole) from None
        try:
            _stages(run, spec, learner, before, recorder, console, progress, expert)
        except DiskFull as full:
            raise _out_of_space(run, full, recorder) from None
        except KeyboardInterrupt as stop:  # between stages: saving final/ or the networks, evaluation's start
            _close(run, recorder)
            with shielded():
                update_meta(run, status="interrupted")
            ckpt = latest_checkpoint(run)
            done = read_state(ckpt)["timesteps"] if ckpt else 0
            raise RunInterrupted(run, done, signal_name(stop)) from None
        except BaseException:
            _close(run, recorder)
            raise
        finally:
            learner.venv.close()  # its worker processes, if any
        _close(run, recorder)
        return run


def _cancel(job: Beside) -> None:
    """Stop a child's work; a second Ctrl-C must not cut the cleanup of a first short."""
    with shielded():
        job.cancel()


def _close(run: Path, recorder: RunRecorder) -> None:
    """Close the recording, held from signals; a full disk becomes RunOutOfSpace."""
    with shielded():
        try:
            recorder.close()
        except DiskFull as full:
            raise _out_of_space(run, full, recorder) from None


def _out_of_space(run: Path, full: DiskFull, recorder: RunRecorder) -> RunOutOfSpace:
    """Close what can be closed on a full disk; the stop to report, with the space a resume needs."""
    with shielded():
        try:
            recorder.close()
        except DiskFull:
            pass
        try:
            update_meta(run, status="stopped: disk full")
        except OSError:
            pass
        whole = recording_problem(recorder.path) is None
    return RunOutOfSpace(run, full, space_to_resume(run), whole)


def _stages(
    run: Path,
    spec: TaskSpec,
    learner,
    before: dict,
    recorder: RunRecorder,
    console: Console,
    progress: bool,
    expert: Beside | None,
) -> None:
    """Train to the budget (checkpointing; Ctrl-C or SIGTERM saves one and stops), save, evaluate, write eval.json."""
    model, venv = learner.model, learner.venv
    monitor = training_monitor(run, spec, learner, recorder, progress, before.get("episodes", 0))
    seconds = before.get("train_seconds", 0.0)
    remaining = spec.train.timesteps - model.num_timesteps
    t0 = time.perf_counter()
    try:
        if remaining > 0 and model.num_timesteps == 0 and spec.train.warm_start is not None:
            warm_start_run(run, spec, learner, recorder, console)  # its time counts in train_seconds
        if remaining > 0:
            learner.learn(remaining, monitor)
    except DiskFull:
        monitor.stop_progress()
        raise
    except KeyboardInterrupt as stop:
        with shielded():
            monitor.stop_progress()
            seconds += time.perf_counter() - t0
            save_checkpoint(
                run / "checkpoints" / f"{model.num_timesteps:010d}",
                model,
                venv,
                {"episodes": monitor.episodes, "train_seconds": seconds},
                learner.parts,
            )
            update_meta(run, status="interrupted", trained_timesteps=int(model.num_timesteps), train_seconds=seconds)
        raise RunInterrupted(run, int(model.num_timesteps), signal_name(stop)) from None
    seconds += time.perf_counter() - t0
    state = {"episodes": monitor.episodes, "train_seconds": seconds, "stopped_early": monitor.stopped_early}
    save_checkpoint(run / "checkpoints" / f"{model.num_timesteps:010d}", model, venv, state, learner.parts)
    save_checkpoint(run / "final", model, venv, state, learner.parts)
    if spec.observation.image is None:  # the safetensors export holds MLPs: a pixel policy stays in final/
        export_networks(run / "networks", learner)
    update_meta(
        run,
        status="evaluating",
        trained_timesteps=int(model.num_timesteps),
        train_seconds=seconds,
        train_fps=model.num_timesteps / max(seconds, 1e-9),
        stopped_early=monitor.stopped_early,
    )
    check_space(recorder.path, 0)  # the reserve, before episodes stream into the recording
    try:
        policy = policy_function(model, venv, spec.evaluate.sampling_seed)
        results = evaluate_run(spec, policy, recorder, console, expert)
    except KeyboardInterrupt as stop:
        with shielded():
            update_meta(run, status="trained, evaluation interrupted")
        raise EvaluationInterrupted(run, signal_name(stop)) from None
    write_json(run / "eval.json", results)
    recorder.log_summary(results["agent"])
    recorder.flush()
    update_meta(run, status="done", eval_seconds=results["eval_seconds"])
