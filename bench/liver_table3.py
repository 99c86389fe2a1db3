"""The paper's Table 3 over several inverse-RL seeds: learned reward and value against economy and safety.

    python bench/liver_table3.py                        # 3 seeds at the spec's budget
    python bench/liver_table3.py --seeds 0 1 2 --timesteps 2000000

Each seed runs `fastrl run specs/liver_tour.yaml --set train.seed=S` (the same synthetic cohort of 100
procedures, GAIL and AIRL with a PPO generator on its 10 best) into runs/bench-liver/<budget>/s<S>; a finished
study there is read back, not rerun. Prints Spearman's rho as mean ± sd over the seeds (the paper reports
0.73 to 0.82 against economy, 0.24 to 0.25 against safety), the largest p-value, the wall time per seed and the
machine. Writes docs/liver_table3_<timesteps or default>.json.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

import numpy as np
from common import machine_line

SPEC = Path("specs/liver_tour.yaml")
CELLS = ("reward-economy", "reward-safety", "value-economy", "value-safety")


def study(seed: int, timesteps: int | None) -> tuple[dict, float]:
    """The Table 3 file (experiment.json) of one seed (run now if not finished before) and the seconds it took now."""
    from rich.console import Console

    from fastrl.runner.study import start_study

    root = Path("runs/bench-liver") / (str(timesteps) if timesteps else "default") / f"s{seed}"
    done = sorted(root.glob("*/*/experiment.json"))
    if done:
        return json.loads(done[-1].read_text()), 0.0
    overrides = [f"train.seed={seed}"] + ([f"study.timesteps={timesteps}"] if timesteps else [])
    t0 = time.perf_counter()
    run = start_study(SPEC, overrides, root=str(root), console=Console(), progress=True)
    return json.loads((run / "experiment.json").read_text()), time.perf_counter() - t0


def summary(results: list[dict]) -> dict:
    """Mean, sd and largest p of every Table 3 cell over the seeds."""
    out = {}
    for algo in [a for a in results[0]["table3"] if a != "heuristic"]:
        for cell in CELLS:
            rho = np.array([r["table3"][algo][cell]["rho"] for r in results], float)
            p = max(r["table3"][algo][cell]["p"] for r in results)
            out[f"{algo}/{cell}"] = {
                "mean": float(rho.mean()),
                "sd": float(rho.std()),
                "max_p": float(p),
                "per_seed": rho.tolist(),
            }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--timesteps", type=int, default=None, help="generator steps per training (default: the spec's)")
    args = ap.parse_args()
    results, seconds = [], []
    for s in args.seeds:
        r, t = study(s, args.timesteps)
        results.append(r)
        seconds.append(t)
    table = summary(results)
    machine = machine_line()
    print(f"\nTable 3 over {len(results)} seeds ({machine}); Spearman's rho mean ± sd (largest p)")
    print("| model | " + " | ".join(CELLS) + " |\n|---|" + "---|" * len(CELLS))
    for algo in ("gail", "airl"):
        cells = [table.get(f"{algo}/{c}") for c in CELLS]
        if all(cells):
            print(
                f"| {algo.upper()} | "
                + " | ".join(f"{c['mean']:.2f} ± {c['sd']:.2f} ({c['max_p']:.0e})" for c in cells)
                + " |"
            )
    h = results[0]["table3"]["heuristic"]
    print(f"heuristic return: economy {h['heuristic-economy']['rho']:.2f}, safety {h['heuristic-safety']['rho']:.2f}")
    timed = [t for t in seconds if t > 0]
    if timed:
        print(f"wall time per seed: {np.mean(timed) / 60:.1f} min (whole study: cohort, 2 trainings, scoring)")
    out = Path(f"docs/liver_table3_{args.timesteps or 'default'}.json")
    out.write_text(
        json.dumps(
            {
                "seeds": args.seeds,
                "timesteps": args.timesteps,
                "machine": machine,
                "seconds": seconds,
                "table3": table,
                "heuristic": results[0]["table3"]["heuristic"],
            },
            indent=2,
        )
    )
    print(f"written {out}")


if __name__ == "__main__":
    main()
