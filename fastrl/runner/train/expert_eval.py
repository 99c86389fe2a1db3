"""The scripted expert's evaluation on a run's seeds: computed beside training, remembered, recalled. Imports
neither torch nor Rerun, so that `fastrl run` can start it before they load."""

from __future__ import annotations

from ...agents.expert import ScriptedExpert
from ...env.fast_env import FastEnv
from ...spec.models import TaskSpec
from .beside import Beside
from .evaluate import evaluate
from .expert_memo import recall, remember


def evaluation_seeds(spec: TaskSpec) -> list[int]:
    """The seeds of the final evaluation's episodes."""
    return [spec.evaluate.seed + i for i in range(spec.evaluate.episodes)]


def expert_beside(spec: TaskSpec, *, idle: bool = False) -> Beside | None:
    """The scripted expert's evaluation (if the spec asks for it) started beside this process where it has a second
    CPU (`train.workers` > 1): its episodes do not depend on the agent. `idle`: at the lowest priority, on the CPU
    time other work leaves (a run starts it before its imports and training)."""
    if not spec.evaluate.expert:
        return None
    seeds = evaluation_seeds(spec)
    known = recall(spec, seeds)
    if known is not None:
        return Beside.ready(known)
    return Beside(lambda: computed_expert_summary(spec, seeds), fork=spec.train.workers > 1, idle=idle)


def expert_summary(spec: TaskSpec, seeds: list[int]) -> dict:
    """The scripted expert's evaluation figures on the given seeds (no images, no recording): computed once per
    spec, seeds and code on this machine, then recalled (3 s of CPU on TraceLines, beside a run's training)."""
    return recall(spec, seeds) or computed_expert_summary(spec, seeds)


def computed_expert_summary(spec: TaskSpec, seeds: list[int]) -> dict:
    """expert_summary's figures computed, and remembered for the next time.

    The expert acts on the task's state, so it goes without image observations: rendering in a child forked
    after this process rendered (the evaluation during training) would deadlock in Mesa's EGL."""
    env = FastEnv(without_images(spec))
    expert = ScriptedExpert(env)
    summary, _ = evaluate(env, expert.act, seeds, on_reset=expert.reset)
    env.close()
    remember(spec, seeds, summary)
    return summary


def without_images(spec: TaskSpec) -> TaskSpec:
    """The spec with the kinematic observation alone."""
    if spec.observation.image is None:
        return spec
    return spec.model_copy(update={"observation": spec.observation.model_copy(update={"image": None})})
