"""A run's evaluation: the agent and the scripted expert on the spec's evaluation seeds; saved runs again."""

from __future__ import annotations

import time
from pathlib import Path

from rich.console import Console

from ...agents.expert import ScriptedExpert
from ...env.fast_env import FastEnv
from ...log import RunRecorder
from ...spec import load_spec
from ...spec.models import TaskSpec
from ..runs.saved import load_policy
from ..runs.stops import EvaluationInterrupted, signal_name, stop_on_sigterm
from .beside import Beside
from .evaluate import evaluate


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

    # the scripted expert's episodes do not depend on the agent: with a second CPU they run beside it
    expert = Beside(lambda: expert_summary(spec, seeds), fork=spec.train.workers > 1) if ev.expert else None
    try:
        agent, _ = evaluate(env, policy, seeds, ev.image_every, ev.record_episodes, on_episode=log)
        out = {"agent": agent, "seeds": seeds}
        if expert is not None:
            out["expert"] = expert.result()
    finally:
        if expert is not None:
            expert.cancel()
        env.close()
    out["eval_seconds"] = time.perf_counter() - t0
    return out


def expert_summary(spec: TaskSpec, seeds: list[int]) -> dict:
    """The scripted expert's evaluation figures on the given seeds (no images, no recording).

    The expert acts on the task's state, so it goes without image observations: rendering in a child forked
    after this process rendered (the evaluation during training) would deadlock in Mesa's EGL."""
    env = FastEnv(without_images(spec))
    expert = ScriptedExpert(env)
    summary, _ = evaluate(env, expert.act, seeds, on_reset=expert.reset)
    env.close()
    return summary


def without_images(spec: TaskSpec) -> TaskSpec:
    """The spec with the kinematic observation alone."""
    if spec.observation.image is None:
        return spec
    return spec.model_copy(update={"observation": spec.observation.model_copy(update={"image": None})})


def evaluate_saved(run: Path, episodes: int | None = None) -> dict:
    """Re-evaluate a saved run's policy without touching its recording (Ctrl-C or SIGTERM: EvaluationInterrupted)."""
    with stop_on_sigterm():
        try:
            spec, policy = load_policy(run)
            if episodes:
                spec = spec.model_copy(update={"evaluate": spec.evaluate.model_copy(update={"episodes": episodes})})
            return evaluate_run(spec, policy, None, None)
        except KeyboardInterrupt as stop:
            raise EvaluationInterrupted(Path(run), signal_name(stop)) from None


def evaluate_expert(spec_path, overrides=(), episodes: int | None = None) -> dict:
    """Evaluate the scripted expert alone on a spec's evaluation seeds."""
    spec = load_spec(spec_path, overrides)
    ev = spec.evaluate
    seeds = [ev.seed + i for i in range(episodes or ev.episodes)]
    t0 = time.perf_counter()
    summary = expert_summary(spec, seeds)
    return {"expert": summary, "seeds": seeds, "eval_seconds": time.perf_counter() - t0}
