"""Saved runs evaluated two ways: the policy's most likely actions (greedy) and its sampled actions.

    python bench/pixel_eval_modes.py RUN [RUN ...] [--json OUT]

Each run's final policy plays the spec's evaluation seeds (20 for tracelines_pixels) once greedily and once with
actions sampled from the policy (`evaluate.sampled`: the draws seeded by the first evaluation seed). Printed per run:
the share of subtasks completed and the success rate each way, and the mean episode time.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

from common import machine_line, utc_stamp  # noqa: E402

from fastrl.env import FastEnv  # noqa: E402
from fastrl.runner.runs.runfiles import read_run_spec  # noqa: E402
from fastrl.runner.runs.saved import checkpoint_policy  # noqa: E402
from fastrl.runner.train.evaluate import evaluate  # noqa: E402


def both_ways(run: Path) -> dict:
    """The run's final policy on its evaluation seeds, greedy and sampled."""
    spec = read_run_spec(run)
    seeds = [spec.evaluate.seed + i for i in range(spec.evaluate.episodes)]
    out = {}
    for sampled in (False, True):
        ev = spec.evaluate.model_copy(update={"sampled": sampled})
        acting = spec.model_copy(update={"evaluate": ev})
        env, t0 = FastEnv(acting), time.perf_counter()
        summary, _ = evaluate(env, checkpoint_policy(acting, run / "final"), seeds)
        env.close()
        out["sampled" if sampled else "greedy"] = {
            "subtasks": summary["subtasks_completed"],
            "success": summary["success_rate"],
            "episode_time": summary["episode_time_mean"],
            "seconds": time.perf_counter() - t0,
        }
    return out


def main() -> None:
    """Evaluate every run both ways and print one line each."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument("--json", type=Path)
    args = p.parse_args()
    print(f"{utc_stamp()}  {machine_line()}", flush=True)
    rows = {}
    for run in args.runs:
        rows[str(run)] = r = both_ways(run)
        g, s = r["greedy"], r["sampled"]
        print(
            f"{run.name}: greedy {g['subtasks']:.1%} of subtasks, success {g['success']:.0%}, {g['episode_time']:.1f} s"
            f" | sampled {s['subtasks']:.1%}, success {s['success']:.0%}, {s['episode_time']:.1f} s",
            flush=True,
        )
    if args.json:
        args.json.write_text(json.dumps({"machine": machine_line(), "utc": utc_stamp(), "runs": rows}, indent=1))


if __name__ == "__main__":
    main()
