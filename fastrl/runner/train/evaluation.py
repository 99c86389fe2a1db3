"""A run's evaluation: the agent and the scripted expert on the spec's evaluation seeds; saved runs again."""

from __future__ import annotations

import time
from functools import partial
from pathlib import Path

from rich.console import Console

from ...env.fast_env import FastEnv
from ...env.render import rendered_here
from ...forked import deferred
from ...log import RunRecorder
from ...spec import load_spec
from ...spec.models import TaskSpec
from ..runs.saved import load_policy
from ..runs.stops import EvaluationInterrupted, shielded, signal_name, stop_on_sigterm
from .beside import Beside, child_or_here
from .evaluate import evaluate, summarize
from .expert_eval import evaluation_seeds, expert_beside, expert_summary


def evaluate_run(
    spec: TaskSpec, policy, recorder: RunRecorder | None, console: Console | None, expert: Beside | None = None
) -> dict:
    """Evaluate a policy (and the scripted expert, if the spec asks) on the spec's evaluation seeds. `expert`: its
    evaluation started earlier at the lowest priority (expert_beside), kept if done, else started afresh here. With a
    second CPU (`train.workers` > 1), the later half of the agent's episodes runs beside this process: the
    episodes are the same either way."""
    ev = spec.evaluate
    seeds = evaluation_seeds(spec)
    t0 = time.perf_counter()
    split = split_across_cores(spec, len(seeds))
    half = len(seeds) // 2 if split else len(seeds)
    rest = partial(agent_episodes, spec, policy, seeds[half:], ev.record_episodes - half)
    jobs, env = [], None
    try:
        with deferred():  # kept in `jobs` before a stop can land
            if expert is not None and not expert.done():  # the idle child found no idle CPU: start afresh beside
                expert.cancel()
                expert = None
            expert = expert or expert_beside(spec)
            later = Beside(rest) if half < len(seeds) else None
            jobs = [job for job in (expert, later) if job is not None]
        env = evaluation_env(spec)

        def log(i, ep):
            if recorder is not None and i < ev.record_episodes:
                recorder.log_episode(i, ep, env.task, spec.scope.fov_deg, ev.image_size)

        episodes = evaluate(env, policy, seeds[:half], ev.image_every, ev.record_episodes, on_episode=log)[1]
        for i, ep in enumerate(child_or_here(later, rest) if later else [], start=half):
            log(i, ep)
            episodes.append(ep)
        out = {"agent": summarize(episodes), "seeds": seeds}
        if expert is not None:
            out["expert"] = expert.result()
    finally:
        with shielded():  # a second Ctrl-C must not cut the cleanup of a first short
            for job in jobs:
                job.cancel()
            if env is not None:
                env.close()
    out["eval_seconds"] = time.perf_counter() - t0
    return out


def split_across_cores(spec: TaskSpec, episodes: int) -> bool:
    """Whether evaluation episodes may run half in a forked child: a second CPU (`train.workers` > 1), more than
    one episode, no sampled actions (their draws follow one another through the episodes) and no render in this
    process yet (a child forked after it would deadlock in Mesa's EGL as soon as it rendered itself)."""
    return episodes > 1 and spec.train.workers > 1 and not spec.evaluate.sampled and not rendered_here()


def evaluation_env(spec: TaskSpec) -> FastEnv:
    """The env of the final evaluation, rendering the recording's endoscope images at their size."""
    return FastEnv(spec, width=spec.evaluate.image_size[0], height=spec.evaluate.image_size[1])


def agent_episodes(spec: TaskSpec, policy, seeds: list[int], record: int) -> list:
    """The policy's evaluation episodes on `seeds`, the first `record` of them with their endoscope images."""
    env = evaluation_env(spec)
    try:
        return evaluate(env, policy, seeds, spec.evaluate.image_every, max(0, record))[1]
    finally:
        env.close()


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
