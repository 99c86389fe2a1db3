"""Do synthetic trainee levels rank by heuristic return? Per-level figures and Kendall's tau-b per task.

    python bench/cohort_levels.py [--levels 5] [--per-level 10] [--seed 0] [--tasks a,b] [--json OUT]

For each task: `make_cohort` on the bundled spec, every trajectory replayed (`data.replay.replay`)
to recompute its heuristic return, subtasks and duration; per level mean and sd; Kendall's tau-b
(scipy) between return and level over all trajectories; whether the level means are in strict order.
With L tied levels of n each, tau-b cannot exceed sqrt(1 - (n-1)/(L*n-1)) (0.904 for 5 x 10).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before anything imports mujoco

import argparse
import json
import time
from pathlib import Path

from common import machine_line
from scipy.stats import kendalltau

from fastrl.data.cohort import level_table, make_cohort, replayed_figures
from fastrl.env.fast_env import FastEnv
from fastrl.spec import load_spec

SPECS = Path(__file__).resolve().parent.parent / "specs"


def measure(task: str, levels: int, per_level: int, seed: int) -> dict:
    """Generate and replay one cohort; its table, tau-b, order and wall times."""
    spec = load_spec(SPECS / f"{task}.yaml")
    env = FastEnv(spec)
    t0 = time.perf_counter()
    cohort = list(make_cohort(spec, levels, per_level, seed, env=env))
    generated = time.perf_counter() - t0
    rows = [{"skill": t.meta["skill"], **replayed_figures(env, t)} for t in cohort]
    tau = kendalltau([r["skill"] for r in rows], [r["return"] for r in rows]).statistic
    pairs = [(a["return"], b["return"]) for a in rows for b in rows if a["skill"] < b["skill"]]
    discordant = sum(lo >= hi for lo, hi in pairs)
    table = level_table(rows)
    means = [e["return"] for e in table]
    ordered = all(a < b for a, b in zip(means, means[1:]))
    return {
        "task": task,
        "table": table,
        "tau_b": float(tau),
        "strict_order": ordered,
        "pairs": len(pairs),
        "discordant": discordant,
        "generate_s": generated,
        "total_s": time.perf_counter() - t0,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, default=5)
    ap.add_argument("--per-level", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--tasks", default="imagecentring,periscoping,tracelines")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    print(f"# {machine_line()}")
    results = []
    for task in a.tasks.split(","):
        r = measure(task, a.levels, a.per_level, a.seed)
        results.append(r)
        print(
            f"\n{task}: tau-b {r['tau_b']:.3f}, level means in strict order: {r['strict_order']}, "
            f"{r['discordant']} of {r['pairs']} cross-level pairs out of order, "
            f"generated in {r['generate_s']:.1f} s (with replay {r['total_s']:.1f} s)"
        )
        print("| level | return | subtasks | duration (s) |")
        print("|---|---|---|---|")
        for e in r["table"]:
            print(
                f"| {e['skill']} | {e['return']:.1f} ± {e['return_sd']:.1f} | {e['subtasks']:.1f} ± "
                f"{e['subtasks_sd']:.1f} | {e['duration']:.1f} ± {e['duration_sd']:.1f} |"
            )
    if a.json:
        a.json.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
