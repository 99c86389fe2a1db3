"""PPO on the heuristic reward of the two-handed triangulation task: steps and wall time to 90% of the subtasks.

    python bench/triangulation_ppo.py [--spec specs/triangulation.yaml] [--cap 2000000] [--seed 0]
                                      [--root runs/bench-instruments] [--set KEY=VALUE ...]

One real `fastrl run` with a deterministic evaluation (10 seeds) every 100k steps, stopped early once an evaluation
completes 95% of the subtasks; prints the machine, the load, the curve, the first evaluation at >= 90% (steps,
wall time) and the final 20-seed evaluation next to the scripted expert's, measured in the same run.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

from common import eval_curve, first_at, load_after, machine_line


def main() -> None:
    """Train, then report."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--spec", default="specs/triangulation.yaml")
    p.add_argument("--cap", type=int, default=2_000_000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--root", default="runs/bench-instruments")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="spec change (repeatable)")
    args = p.parse_args()
    from fastrl.runner import start_run

    print(f"# machine: {machine_line()}")
    changes = [
        f"train.timesteps={args.cap}",
        f"train.seed={args.seed}",
        "evaluate.periodic_every=100000",
        "evaluate.periodic_episodes=10",
        "evaluate.stop_at_subtasks=0.95",
        "evaluate.record_episodes=2",
        "evaluate.image_every=8",
        *args.set,
    ]
    t0 = time.perf_counter()
    run = start_run(Path(args.spec), changes, args.root, progress=False)
    wall = time.perf_counter() - t0
    steps, subtasks, seconds = eval_curve(run)
    print("| timesteps | eval subtasks | train seconds |")
    print("|---|---|---|")
    for step, share, secs in zip(steps, subtasks, seconds):
        print(f"| {step:,} | {share:.1%} | {secs:.0f} |")
    i = first_at(subtasks, 0.9)
    hit = None if i is None else (steps[i], seconds[i])
    meta = json.loads((run / "meta.json").read_text())
    ev = json.loads((run / "eval.json").read_text())
    print(f"run: {run} (wall {wall:.0f} s incl. evaluation and recording)")
    print(f"trained {meta['trained_timesteps']:,} steps in {meta['train_seconds']:.0f} s")
    print(
        f"first evaluation >= 90% of subtasks: {'not reached' if hit is None else f'{hit[0]:,} steps, {hit[1]:.0f} s'}"
    )
    agent, expert = ev["agent"], ev["expert"]
    print(
        f"final ({agent.get('episodes', '?')} episodes): agent {agent['subtasks_completed']:.1%} subtasks, "
        f"success {agent['success_rate']:.0%}; scripted expert {expert['subtasks_completed']:.1%}"
    )
    print(load_after())


if __name__ == "__main__":
    main()
