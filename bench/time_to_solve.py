"""Wall time to >= 95% of subtasks per FAST task: `fastrl run` (its spec's PPO or SAC) against plain SB3 defaults.

    python bench/time_to_solve.py [--algo PPO] [--tasks imagecentring periscoping tracelines] [--seeds 0 1 2]
                                  [--sb3-seeds 0] [--sb3-cap 180] [--eval-every 10000] [--json OUT]
    python bench/time_to_solve.py --algo SAC --tasks tracelines --sb3-cap 600 --eval-every 5000

--algo SAC: fastrl's side is `fastrl run SPEC --algo SAC --set actions.mode=rates` (the spec's `train.sac`
settings), SB3's side stable-baselines3 SAC at its library defaults (1 env, 1 update of batch 256 per step,
[256, 256], learning_starts 100, no normalisation) on the same `rates` env, with one torch thread (two threads
make its update 8x slower on a 2-core machine: in its favour).

fastrl: each seed is one `start_run` of specs/<task>.yaml (the code path of `fastrl run SPEC --seed S`, its
periodic evaluation and early stop as the spec sets them), in a fresh Python process importing the fastrl of
the checkout the bench is in (PYTHONPATH), so a worktree of another commit times that commit. Time to 95% runs from
the process start (imports included) to the end of the first periodic evaluation at >= 95% of subtasks; the
whole command adds the final evaluation, the expert's and the recording. The median over seeds is reported.

SB3: stable-baselines3 PPO at its library defaults (MlpPolicy, n_steps 2048, batch 64, 10 epochs, [64, 64],
no normalisation, torch's default threads) on FastEnv of the same spec through SB3's own `make_vec_env`
(1 env, DummyVecEnv, Monitor), in a fresh process. Every --eval-every steps it is evaluated like fastrl's
periodic evaluation (the spec's first `evaluate.periodic_episodes` evaluation seeds, deterministic); the
evaluation time is left out of its clock (in its favour). It stops at 95% or after --sb3-cap seconds of
training ("not reached in X s").
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("CI", "1")

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import load_average, machine_line

ROOT = Path(__file__).resolve().parent.parent
TASKS = ("imagecentring", "periscoping", "tracelines")
MARK = 0.95


ALGO_SETS = {"PPO": [], "SAC": ["train.algo=SAC", "actions.mode=rates"]}  # fastrl's side, before --set


def fastrl_side(task: str, seed: int, out: Path, sets: list[str]) -> None:
    """One `fastrl run` in this process; its periodic evaluations (timesteps, subtasks, time) into out."""
    from fastrl.runner.train import monitoring
    from fastrl.runner.train import run as run_stage

    events = []
    wrapped = monitoring.periodic_evaluator

    def timed_evaluator(spec, model, venv):
        inner = wrapped(spec, model, venv)

        def evaluation():
            t0 = time.time()
            result = inner()
            events.append([int(model.num_timesteps), result["eval/subtasks"], time.time(), time.time() - t0])
            return result

        return None if inner is None else evaluation

    monitoring.periodic_evaluator = timed_evaluator
    with tempfile.TemporaryDirectory() as root:
        run = run_stage.start_run(ROOT / "specs" / f"{task}.yaml", [f"train.seed={seed}", *sets], root, progress=False)
        meta = json.loads((run / "meta.json").read_text())
        final = json.loads((run / "eval.json").read_text())["agent"]["subtasks_completed"]
    steps_per_s = meta["trained_timesteps"] / meta["train_seconds"]
    out.write_text(json.dumps({"events": events, "final": final, "steps_per_s": steps_per_s, "end": time.time()}))


def sb3_side(task: str, seed: int, out: Path, cap: float, every: int, algo: str) -> None:
    """Plain SB3 PPO or SAC at its defaults on FastEnv, evaluated every `every` steps until 95% or `cap` seconds."""
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env

    from fastrl.env.fast_env import FastEnv
    from fastrl.runner.train.evaluate import evaluate_batched
    from fastrl.spec import load_spec

    spec = load_spec(ROOT / "specs" / f"{task}.yaml", ALGO_SETS[algo])
    seeds = [spec.evaluate.seed + i for i in range(spec.evaluate.periodic_episodes)]
    envs = [FastEnv(spec) for _ in seeds]
    if algo == "SAC":
        torch.set_num_threads(1)
    learner = {"PPO": PPO, "SAC": SAC}[algo]
    model = learner("MlpPolicy", make_vec_env(lambda: FastEnv(spec), seed=seed), seed=seed, device="cpu")
    events, clock = [], {"train": 0.0, "since": time.perf_counter(), "next": every}

    class Evaluate(BaseCallback):
        """Evaluate every `every` steps; stop at the mark or the cap."""

        def _on_step(self) -> bool:
            if self.num_timesteps < clock["next"]:
                return True
            clock["train"] += time.perf_counter() - clock["since"]
            clock["next"] += every
            t0 = time.perf_counter()
            s = evaluate_batched(envs, lambda o: model.predict(o, deterministic=True)[0], seeds)
            events.append([self.num_timesteps, s["subtasks_completed"], clock["train"], time.perf_counter() - t0])
            clock["since"] = time.perf_counter()
            return s["subtasks_completed"] < MARK and clock["train"] < cap

    model.learn(100_000_000, callback=Evaluate())
    out.write_text(json.dumps({"events": events, "steps_per_s": model.num_timesteps / max(clock["train"], 1e-9)}))


def child(args: list[str]) -> dict:
    """Run one side in a fresh process; its result with the process start time."""
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "out.json"
        t0 = time.time()
        env = os.environ | {"PYTHONPATH": str(ROOT)}  # this checkout's fastrl, not whichever one is installed
        cmd = [sys.executable, __file__, *args, "--out", str(out)]
        res = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if res.returncode != 0:
            raise SystemExit(res.stderr[-3000:])
        result = json.loads(out.read_text())
        result["start"], result["exit"] = t0, time.time()
        return result


def first_at_mark(events: list, start: float = 0.0):
    """(timesteps, seconds) of the first evaluation at >= 95% of subtasks, or None."""
    for steps, share, t, _ in events:
        if share >= MARK:
            return steps, t - start
    return None


def main() -> None:
    """Both sides per task, then the table."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--algo", choices=list(ALGO_SETS), default="PPO", help="fastrl's spec settings and SB3's class")
    ap.add_argument("--tasks", nargs="+", default=list(TASKS), choices=TASKS)
    ap.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    ap.add_argument("--sb3-seeds", nargs="*", type=int, default=[0])
    ap.add_argument("--sb3-cap", type=float, default=180.0, help="seconds of SB3 training before giving up")
    ap.add_argument("--eval-every", type=int, default=10_000, help="SB3's steps between evaluations")
    ap.add_argument("--set", action="append", default=[], help="an override of fastrl's spec (KEY=VALUE), repeatable")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--side", choices=["fastrl", "sb3"], help=argparse.SUPPRESS)
    ap.add_argument("--task", help=argparse.SUPPRESS)
    ap.add_argument("--seed", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.side == "fastrl":
        return fastrl_side(args.task, args.seed, args.out, [*ALGO_SETS[args.algo], *args.set])
    if args.side == "sb3":
        return sb3_side(args.task, args.seed, args.out, args.sb3_cap, args.eval_every, args.algo)
    print(
        f"{args.algo}: time to {MARK:.0%} of subtasks  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  "
        f"{machine_line()}"
    )
    if args.set:
        print(f"fastrl overrides: {' '.join(args.set)}")
    report = {"algo": args.algo, "machine": machine_line(), "tasks": {}}
    for task in args.tasks:
        rows = {"fastrl": [], "sb3": []}
        for seed in args.seeds:
            r = child(
                ["--algo", args.algo, "--side", "fastrl", "--task", task, "--seed", str(seed)]
                + [f"--set={kv}" for kv in args.set]
            )
            hit = first_at_mark(r["events"], r["start"])
            rows["fastrl"].append({"seed": seed, "hit": hit, "whole": r["exit"] - r["start"], **r})
            print(
                f"  {task:14s} fastrl seed {seed}: "
                + (f"{hit[1]:6.1f} s ({hit[0]} steps)" if hit else "not reached")
                + f", whole command {r['exit'] - r['start']:.1f} s, final evaluation {r['final']:.0%}, "
                f"{r['steps_per_s']:.0f} steps/s, evaluations {sum(e[3] for e in r['events']):.1f} s",
                flush=True,
            )
        for seed in args.sb3_seeds:
            r = child(
                [
                    "--algo",
                    args.algo,
                    "--side",
                    "sb3",
                    "--task",
                    task,
                    "--seed",
                    str(seed),
                    "--sb3-cap",
                    str(args.sb3_cap),
                    "--eval-every",
                    str(args.eval_every),
                ]
            )
            hit = first_at_mark(r["events"])
            rows["sb3"].append({"seed": seed, "hit": hit, **r})
            best = max((e[1] for e in r["events"]), default=0.0)
            print(
                f"  {task:14s} SB3    seed {seed}: "
                + (
                    f"{hit[1]:6.1f} s ({hit[0]} steps)"
                    if hit
                    else f"not reached in {args.sb3_cap:.0f} s (best {best:.0%})"
                )
                + f", {r['steps_per_s']:.0f} steps/s",
                flush=True,
            )
        times = [r["hit"][1] if r["hit"] else float("inf") for r in rows["fastrl"]]
        sb3 = [r["hit"][1] for r in rows["sb3"] if r["hit"]]
        fastrl = (
            f"fastrl median {statistics.median(times):.1f} s to {MARK:.0%} ({len(times)} seeds), "
            f"{statistics.median(r['steps_per_s'] for r in rows['fastrl']):.0f} steps/s"
            if times
            else "fastrl not run"
        )
        print(
            f"{task:14s} {fastrl} | SB3 defaults "
            + (f"{statistics.median(sb3):.1f} s" if len(sb3) == len(rows["sb3"]) and sb3 else "not reached")
            + f", {statistics.median(r['steps_per_s'] for r in rows['sb3']) if rows['sb3'] else 0:.0f} steps/s"
            f"  (load now {load_average()})",
            flush=True,
        )
        report["tasks"][task] = rows
    if args.json:
        args.json.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
