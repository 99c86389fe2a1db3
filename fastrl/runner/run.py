"""The stages of one run: prepare the run directory, train, checkpoint, evaluate, record."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
from rich.console import Console

from ..agents.expert import ScriptedExpert
from ..agents.sb3 import load_checkpoint, policy_function, save_checkpoint
from ..env.fast_env import FastEnv
from ..irl.export import save_networks
from ..log import RunRecorder
from ..model.compiler import CompiledTask, compile_task
from ..spec import load_spec
from ..spec.models import TaskSpec
from .evaluate import evaluate
from .learner import build_learner
from .monitor import TrainingMonitor
from .rundir import latest_checkpoint, new_run_dir, update_meta, write_meta, write_spec
from .saved import load_policy


class RunInterrupted(Exception):
    """Training was stopped by the user; the run can be resumed."""

    def __init__(self, run: Path, timesteps: int):
        super().__init__(f"interrupted at {timesteps} timesteps")
        self.run, self.timesteps = run, timesteps


class EvaluationInterrupted(Exception):
    """Evaluation was stopped by the user; the trained policy is saved in final/."""

    def __init__(self, run: Path):
        super().__init__("evaluation interrupted")
        self.run = run


def start_run(
    spec_path,
    overrides=(),
    root="runs",
    console: Console | None = None,
    progress: bool = True,
    into: Path | None = None,
) -> Path:
    """Train, evaluate and record a new run of a spec file (in `into` if given); return its directory."""
    spec = load_spec(spec_path, overrides)
    task = compile_task(spec)
    if into is not None:
        Path(into).mkdir(parents=True, exist_ok=False)
    run = Path(into) if into is not None else new_run_dir(Path(root), spec)
    write_spec(run, spec, task.xml)
    write_meta(run, spec, str(spec_path), {"status": "training", "overrides": list(overrides)})
    return _train_and_evaluate(run, spec, task, None, console or Console(), progress)


def resume_run(run: Path, console: Console | None = None, progress: bool = True, timesteps: int | None = None) -> Path:
    """Continue a run from its newest checkpoint to its budget (or a new one), then evaluate and record."""
    run = Path(run)
    if not (run / "spec.yaml").exists():
        raise FileNotFoundError(f"{run} is not a run directory (no spec.yaml)")
    spec = load_spec(run / "spec.yaml", [f"train.timesteps={timesteps}"] if timesteps else [])
    task = compile_task(spec)
    if timesteps:
        write_spec(run, spec, task.xml)
    ckpt = latest_checkpoint(run)
    if ckpt is None:
        raise FileNotFoundError(f"{run} has no checkpoint to resume from")
    return _train_and_evaluate(run, spec, task, ckpt, console or Console(), progress)


def _open_recorder(run: Path, spec: TaskSpec, task: CompiledTask, resuming: bool) -> RunRecorder:
    """The run's recording; a resumed run keeps the old file aside and re-logs the curves so far."""
    path = run / "recording.rrd"
    if resuming and path.exists():
        k = len(list(run.glob("recording.part*.rrd"))) + 1
        path.rename(run / f"recording.part{k}.rrd")
    recorder = RunRecorder(path, recording_id=run.name, run_name=f"{spec.name} {run.name}")
    recorder.log_scene(task)
    n = min(spec.evaluate.record_episodes, spec.evaluate.episodes)
    recorder.send_blueprint(n, spec.irl.enabled, curves=spec.irl.algorithm != "bc")  # BC logs no curves
    if resuming:
        history = (
            [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines() if line.strip()]
            if (run / "metrics.jsonl").exists()
            else []
        )
        if history:
            keys = sorted({k for row in history for k in row} - {"timesteps"})
            recorder.log_training_columns(
                np.array([r["timesteps"] for r in history]),
                {k: np.array([r.get(k, np.nan) for r in history], float) for k in keys},
            )
    return recorder


def _train_and_evaluate(
    run: Path, spec: TaskSpec, task: CompiledTask, ckpt: Path | None, console: Console, progress: bool
) -> Path:
    """Train (from a checkpoint if given), save, evaluate agent and expert, write eval.json and the recording."""
    learner = build_learner(spec, run, console, progress)
    model, venv = learner.model, learner.venv
    before = load_checkpoint(ckpt, model, venv, learner.parts) if ckpt else {}
    recorder = _open_recorder(run, spec, task, resuming=ckpt is not None)
    try:
        ev = spec.evaluate
        monitor = TrainingMonitor(
            run,
            list(spec.reward.features),
            total=spec.train.timesteps,
            log_every=spec.train.log_every,
            checkpoint_every=spec.train.checkpoint_every,
            recorder=recorder,
            progress=progress,
            keep_checkpoints=spec.train.keep_checkpoints,
            stats=learner.stats,
            parts=learner.parts,
            evaluator=periodic_evaluator(spec, model, venv),
            eval_every=ev.periodic_every,
            stop_at=ev.stop_at_subtasks,
        )
        monitor.episodes = before.get("episodes", 0)
        seconds = before.get("train_seconds", 0.0)
        remaining = spec.train.timesteps - model.num_timesteps
        t0 = time.perf_counter()
        try:
            if remaining > 0:
                learner.learn(remaining, monitor)
        except KeyboardInterrupt:
            monitor.progress.stop()
            seconds += time.perf_counter() - t0
            save_checkpoint(
                run / "checkpoints" / f"{model.num_timesteps:010d}",
                model,
                venv,
                {"episodes": monitor.episodes, "train_seconds": seconds},
                learner.parts,
            )
            update_meta(run, status="interrupted", trained_timesteps=int(model.num_timesteps), train_seconds=seconds)
            raise RunInterrupted(run, int(model.num_timesteps)) from None
        seconds += time.perf_counter() - t0
        state = {"episodes": monitor.episodes, "train_seconds": seconds, "stopped_early": monitor.stopped_early}
        save_checkpoint(run / "checkpoints" / f"{model.num_timesteps:010d}", model, venv, state, learner.parts)
        save_checkpoint(run / "final", model, venv, state, learner.parts)
        save_networks(run / "networks", model, venv, learner.disc, spec.train.params().gamma, learner.snapshots)
        update_meta(
            run,
            status="evaluating",
            trained_timesteps=int(model.num_timesteps),
            train_seconds=seconds,
            train_fps=model.num_timesteps / max(seconds, 1e-9),
            stopped_early=monitor.stopped_early,
        )
        try:
            results = evaluate_run(spec, policy_function(model, venv), recorder, console)
        except KeyboardInterrupt:
            update_meta(run, status="trained, evaluation interrupted")
            raise EvaluationInterrupted(run) from None
        (run / "eval.json").write_text(json.dumps(results, indent=2))
        recorder.log_summary(results["agent"])
        update_meta(run, status="done", eval_seconds=results["eval_seconds"])
    finally:
        recorder.close()
    return run


def periodic_evaluator(spec: TaskSpec, model, venv):
    """Deterministic evaluation of the current policy on the first evaluation seeds, as curve points."""
    if not spec.evaluate.periodic_every:
        return None
    env = FastEnv(spec)
    seeds = [spec.evaluate.seed + i for i in range(spec.evaluate.periodic_episodes)]

    def run_evaluation() -> dict[str, float]:
        summary, _ = evaluate(env, policy_function(model, venv), seeds)
        return {
            "eval/success_rate": summary["success_rate"],
            "eval/subtasks": summary["subtasks_completed"],
            "eval/return": summary["return_mean"],
            "eval/episode_time": summary["episode_time_mean"],
        }

    return run_evaluation


def evaluate_run(spec: TaskSpec, policy, recorder: RunRecorder | None, console: Console | None) -> dict:
    """Evaluate a policy (and the scripted expert, if the spec asks) on the spec's evaluation seeds."""
    ev = spec.evaluate
    seeds = [ev.seed + i for i in range(ev.episodes)]
    env = FastEnv(spec, width=ev.image_size[0], height=ev.image_size[1])
    task = env.task
    t0 = time.perf_counter()

    def log(i, ep):
        if recorder is not None and i < ev.record_episodes:
            recorder.log_episode(i, ep, task, spec.scope.fov_deg, ev.image_size)

    agent, _ = evaluate(env, policy, seeds, ev.image_every, ev.record_episodes, on_episode=log)
    out = {"agent": agent, "seeds": seeds}
    if ev.expert:
        expert = ScriptedExpert(env)
        out["expert"], _ = evaluate(env, expert.act, seeds, on_reset=expert.reset)
    out["eval_seconds"] = time.perf_counter() - t0
    env.close()
    return out


def evaluate_saved(run: Path, episodes: int | None = None) -> dict:
    """Re-evaluate a saved run's policy without touching its recording."""
    spec, policy = load_policy(run)
    if episodes:
        spec = spec.model_copy(update={"evaluate": spec.evaluate.model_copy(update={"episodes": episodes})})
    return evaluate_run(spec, policy, None, None)


def evaluate_expert(spec_path, overrides=(), episodes: int | None = None) -> dict:
    """Evaluate the scripted expert alone on a spec's evaluation seeds."""
    spec = load_spec(spec_path, overrides)
    ev = spec.evaluate
    seeds = [ev.seed + i for i in range(episodes or ev.episodes)]
    env = FastEnv(spec)
    expert = ScriptedExpert(env)
    t0 = time.perf_counter()
    summary, _ = evaluate(env, expert.act, seeds, on_reset=expert.reset)
    return {"expert": summary, "seeds": seeds, "eval_seconds": time.perf_counter() - t0}
