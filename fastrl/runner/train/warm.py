"""A run's warm start: the expert's clone refined by DAgger, each round in warm_start.jsonl and the recording."""

from __future__ import annotations

import json
import time
from pathlib import Path

from rich.console import Console

from ...agents.anchor import CloneAnchor
from ...agents.dagger import warm_start
from ...atomic import append_line
from ...env.fast_env import FastEnv
from ...log import RunRecorder
from ...spec.models import TaskSpec
from ..runs.rundir import update_meta

SEED_STRIDE = 100_000  # the warm start's episode seeds start at train.seed x this, apart from evaluation's


def warm_start_run(run: Path, spec: TaskSpec, learner, recorder: RunRecorder, console: Console) -> float:
    """Fit the learner's policy by the spec's `train.warm_start` (and hold PPO near its data if it has an anchor);
    return the seconds it took. A run resumed after PPO's first checkpoint goes on without the anchor."""
    cfg = spec.train.warm_start
    t0 = time.perf_counter()

    def log(row: dict) -> None:
        append_line(run / "warm_start.jsonl", json.dumps(row))
        recorder.log_warm_start(row["dagger_pairs"], row)
        what = "clone of the expert" if row["dagger_round"] == 0 else f"DAgger round {row['dagger_round']}"
        console.print(
            f"warm start, {what}: {row['dagger_pairs']:,} labelled steps, loss {row['dagger_loss']:.3f}, "
            f"action accuracy {row['dagger_accuracy']:.2f}, its episodes completed {row['dagger_subtasks']:.0%} "
            f"of subtasks ({row['dagger_seconds']:.0f} s)",
            markup=False,
            highlight=False,
        )

    env = FastEnv(spec)
    try:
        rows, data = warm_start(
            learner.model,
            learner.venv,
            env,
            **cfg.model_dump(exclude={"anchor"}),
            seed=SEED_STRIDE * spec.train.seed,
            log=log,
        )
    finally:
        env.close()
    if cfg.anchor:
        learner.callbacks.append(CloneAnchor(data.obs, data.labels, steps=cfg.anchor, seed=spec.train.seed))
    seconds = time.perf_counter() - t0
    update_meta(run, warm_start={"rounds": len(rows), "pairs": rows[-1]["dagger_pairs"], "seconds": seconds})
    return seconds
