"""A run's training callbacks, built from its spec: tally, progress, periodic evaluations, curves, checkpoints."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np

from ...agents.sb3 import batch_policy
from ...env.fast_env import FastEnv
from ...forked import deferred, idle_work_running
from ...log import RunRecorder
from ...spec.irl import min_steps, stop_at_subtasks
from ...spec.models import TaskSpec
from ..runs.stops import shielded
from .beside import Beside, child_or_here
from .evaluate import batched_episodes, batched_summary
from .evaluation import split_across_cores
from .monitor import (
    Checkpoints,
    CurvePoints,
    EpisodeTally,
    PeriodicEvaluation,
    ProgressBar,
    StopAtSubtasks,
    TrainingMonitor,
)


def training_monitor(
    run: Path, spec: TaskSpec, learner, recorder: RunRecorder, progress: bool, episodes: int
) -> TrainingMonitor:
    """The run's training callbacks: tally, progress bar, evaluations, curve points, checkpoints, early stop."""
    tally = EpisodeTally(feature_names=list(spec.reward.features), episodes=episodes)
    bar = ProgressBar(total=spec.train.timesteps, enabled=progress)
    evaluator = periodic_evaluator(spec, learner.model, learner.venv)
    evaluation = None
    if evaluator is not None:
        evaluation = PeriodicEvaluation(evaluator=evaluator, every=periodic_every(spec), status=bar.status)
    points = CurvePoints(
        run=run,
        tally=tally,
        log_every=spec.train.log_every,
        evaluation=evaluation,
        stats=learner.stats,
        sinks=[recorder.log_training, bar.show_point],
    )
    train = spec.train
    checkpoints = Checkpoints(
        run=run,
        every=train.checkpoint_every,
        keep=train.keep_checkpoints,
        tally=tally,
        parts=learner.parts,
        before_save=recorder.flush,
    )
    stop_at = stop_at_subtasks(spec.train, spec.irl, spec.evaluate.stop_at_subtasks)
    after = min_steps(spec.train, spec.irl)
    stop = []
    if evaluation and stop_at is not None:
        stop = [StopAtSubtasks(evaluation=evaluation, at=stop_at, after=after)]
    return TrainingMonitor([tally, bar, *([evaluation] if evaluation else []), points, checkpoints, *stop])


def periodic_every(spec: TaskSpec) -> int:
    """Timesteps between evaluations during training (0: none): the algorithm's own cadence, or the spec's."""
    return getattr(spec.train.params(), "periodic_every", None) or spec.evaluate.periodic_every


def periodic_evaluator(spec: TaskSpec, model, venv):
    """Evaluation of the current policy on the first evaluation seeds (its sampled actions if the spec says so), as
    curve points.

    The episodes run side by side, one policy call for all of them per step; with a second CPU (`train.workers` >
    1) and no work at the lowest priority beside, the later half of them in a forked child meanwhile (the env
    workers wait: the same figures either way)."""
    if not periodic_every(spec):
        return None
    seeds = [spec.evaluate.seed + i for i in range(spec.evaluate.periodic_episodes)]
    envs = [FastEnv(spec) for _ in seeds]

    def run_evaluation() -> dict[str, float]:
        act = batch_policy(model, venv, spec.evaluate.sampling_seed)
        # the CPU time the env workers leave belongs to the scripted expert's evaluation while it runs beside at the
        # lowest priority (else the final evaluation waits for it)
        split = split_across_cores(spec, len(seeds)) and not idle_work_running()
        half = len(seeds) // 2 if split else len(seeds)
        rest = partial(batched_episodes, envs[half:], act, seeds[half:])
        later = None
        try:
            with deferred():  # cancelled below even if a stop lands as it starts
                later = Beside(rest) if split else None
            mine = batched_episodes(envs[:half], act, seeds[:half])
            theirs = child_or_here(later, rest) if later is not None else np.zeros((0, 4))
        finally:
            if later is not None:
                with shielded():
                    later.cancel()
        summary = batched_summary(np.concatenate([mine, theirs]))
        return {
            "eval/success_rate": summary["success_rate"],
            "eval/subtasks": summary["subtasks_completed"],
            "eval/return": summary["return_mean"],
            "eval/episode_time": summary["episode_time_mean"],
        }

    return run_evaluation
