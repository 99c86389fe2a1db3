"""Where the wall time of a `fastrl run` goes: env stepping, learner, rendering, Rerun logging, checkpoints.

    python bench/run_profile.py [--spec specs/tracelines.yaml] [--timesteps 50000] [--episodes 5] [--set KEY=VALUE]

Runs the real runner (fastrl.runner.start_run) into a temporary runs folder with timers wrapped
around the vectorised env's step, the evaluation env's step and render, and every RunRecorder
call and every checkpoint save. The learner's share is the training time not spent stepping envs, logging
or checkpointing (with `train.workers` > 1 the env stepping is the main process stepping its batch and
waiting for the workers'; periodic evaluation counts as callbacks). The last line is issue 29's budget:
Rerun logging during training plus checkpoints (periodic and final) as a share of the training time, to
stay under 5%. Reported, never asserted.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("CI", "1")

import argparse
import functools
import json
import tempfile
import time
from collections import defaultdict
from pathlib import Path

from common import machine_line

from fastrl.agents.workers import FreshInfoVecEnv, SplitVecEnv
from fastrl.env.fast_env import FastEnv
from fastrl.log import RunRecorder
from fastrl.runner import start_run
from fastrl.runner.train import monitor as run_monitor
from fastrl.runner.train import run as run_stage

TIMERS: dict[str, float] = defaultdict(float)
CALLS: dict[str, int] = defaultdict(int)
IN_VEC = [False]


def timed(name: str, fn, skip_inside_vec: bool = False):
    """Wrap fn so its wall time accumulates under name."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if skip_inside_vec and IN_VEC[0]:
            return fn(*args, **kwargs)
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            TIMERS[name] += time.perf_counter() - t0
            CALLS[name] += 1

    return wrapper


def vec_step(fn):
    """Time the vectorised env step and mark it so the inner env steps are not counted twice."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if IN_VEC[0]:  # the split env's own batch, inside its step_wait
            return fn(*args, **kwargs)
        IN_VEC[0] = True
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            TIMERS["train: env stepping (vec env)"] += time.perf_counter() - t0
            CALLS["train: env stepping (vec env)"] += 1
            IN_VEC[0] = False

    return wrapper


def instrument() -> None:
    """Install the timers."""
    FreshInfoVecEnv.step_wait = vec_step(FreshInfoVecEnv.step_wait)
    SplitVecEnv.step_wait = vec_step(SplitVecEnv.step_wait)
    FastEnv.step = timed("eval: env stepping", FastEnv.step, skip_inside_vec=True)
    FastEnv.render_views = timed("eval: endoscope rendering", FastEnv.render_views)
    for name in (
        "log_scene",
        "log_episode",
        "log_training",
        "log_training_columns",
        "log_summary",
        "send_blueprint",
        "close",
    ):
        setattr(RunRecorder, name, timed(f"logging: {name}", getattr(RunRecorder, name)))
    run_monitor.save_checkpoint = timed("checkpointing: periodic (in training)", run_monitor.save_checkpoint)
    run_stage.save_checkpoint = timed("checkpointing: last and final (after training)", run_stage.save_checkpoint)


def main() -> None:
    """Run once and print the shares."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spec", default="specs/tracelines.yaml")
    ap.add_argument("--timesteps", type=int, default=50_000)
    ap.add_argument("--episodes", type=int, default=5)
    ap.add_argument("--set", action="append", default=[], help="a spec override (KEY=VALUE), repeatable")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    instrument()
    with tempfile.TemporaryDirectory() as root:
        t0 = time.perf_counter()
        run = start_run(
            args.spec,
            [f"train.timesteps={args.timesteps}", f"evaluate.episodes={args.episodes}", *args.set],
            root,
            progress=False,
        )
        wall = time.perf_counter() - t0
        meta = json.loads((run / "meta.json").read_text())
    train = meta["train_seconds"]
    logging = sum(v for k, v in TIMERS.items() if k.startswith("logging"))
    rows = dict(TIMERS)
    rows["train: learner and callbacks (rest of training)"] = (
        train
        - TIMERS["train: env stepping (vec env)"]
        - TIMERS["logging: log_training"]
        - TIMERS["logging: log_training_columns"]
        - TIMERS["checkpointing: periodic (in training)"]
    )
    print(f"fastrl run profile  {machine_line()}")
    print(
        f"spec {args.spec} {' '.join(args.set)}  timesteps {meta['trained_timesteps']}  eval episodes {args.episodes}"
    )
    print(f"wall {wall:.1f} s  (training {train:.1f} s, {meta['trained_timesteps'] / train:.0f} steps/s)\n")
    print(f"{'part':52s} {'seconds':>9s} {'share':>7s} {'calls':>8s}")
    for name, sec in sorted(rows.items(), key=lambda kv: -kv[1]):
        print(f"{name:52s} {sec:9.2f} {sec / wall:7.1%} {CALLS.get(name, 0):8d}")
    print(
        f"\n{'env stepping (training + evaluation)':52s} "
        f"{TIMERS['train: env stepping (vec env)'] + TIMERS['eval: env stepping']:9.2f} "
        f"{(TIMERS['train: env stepping (vec env)'] + TIMERS['eval: env stepping']) / wall:7.1%}"
    )
    print(f"{'Rerun logging (all calls)':52s} {logging:9.2f} {logging / wall:7.1%}")
    during = TIMERS["logging: log_training"] + TIMERS["logging: log_training_columns"]
    periodic = TIMERS["checkpointing: periodic (in training)"]
    saving = periodic + TIMERS["checkpointing: last and final (after training)"]
    print(f"{'checkpoints (all saves)':52s} {saving:9.2f} {saving / wall:7.1%}")
    print(
        f"{'Rerun logging + checkpoints (issue 29: < 5%)':52s} {logging + saving:9.2f} {(logging + saving) / wall:7.1%}"
    )
    print(
        f"{'  of which during training (curves, periodic saves)':52s} {during + periodic:9.2f} "
        f"{(during + periodic) / train:7.1%} of training"
    )
    if args.json:
        args.json.write_text(
            json.dumps({"wall": wall, "train_seconds": train, "parts": rows, "logging": logging}, indent=2)
        )


if __name__ == "__main__":
    main()
