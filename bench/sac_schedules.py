"""SAC update schedules on TraceLines: final performance at the same step budget, and the wall time it costs.

    python bench/sac_schedules.py run --schedules sb3 lean-128 --seeds 0 1 2     # ~15 min per sb3 run
    python bench/sac_schedules.py report

Every run is `fastrl run specs/tracelines.yaml --algo SAC --set actions.mode=rates` (first-order actions, where
SAC learns; heuristic reward) on --steps environment steps with a 10-seed deterministic evaluation every
--eval-every steps and the usual 20-seed final evaluation. `sb3` is stable-baselines3's SAC as it comes (1 env,
one update of batch 256 per step, [256, 256]): the reference. The report gives final subtasks and success
(mean ± sd over seeds), training wall time and steps/s (evaluations excluded), the speed-up over `sb3` measured
in the same report, and a figure of subtasks over steps. Runs that ran side by side share the 2 cores, so
compare speeds within one batch; bench/sac_speed.py times the schedules alone.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

import numpy as np
from common import eval_curve, label_curve_axes, machine_line, plot_mean_range, save_figure

SCHEDULES = {
    # name: (what differs from the reference, spec overrides)
    "sb3": ("stable-baselines3 SAC: 1 env, 1 update / step, [256, 256]", ["train.sac.lean_update=false"]),
    "lean": ("same schedule, fastrl's lean update", []),
    "lean-128": ("lean, [128, 128]", ["train.sac.net_arch=[128, 128]"]),
    "lean-128-b128": ("lean, [128, 128], batch 128", ["train.sac.net_arch=[128, 128]", "train.sac.batch_size=128"]),
    "lean-128-half": (
        "lean, [128, 128], 1 update / 2 steps",
        ["train.sac.net_arch=[128, 128]", "train.sac.train_freq=2"],
    ),
    "lean-128-4env-half": (
        "lean, [128, 128], 4 envs, 2 updates / 4 steps",
        ["train.sac.net_arch=[128, 128]", "train.n_envs=4", "train.sac.gradient_steps=2"],
    ),
    "lean-128-4env-quarter": (
        "lean, [128, 128], 4 envs, 1 update / 4 steps",
        ["train.sac.net_arch=[128, 128]", "train.n_envs=4", "train.sac.gradient_steps=1"],
    ),
    "lean-128-4env-quarter-lr1e-3": (
        "the same, learning rate 1e-3",
        [
            "train.sac.net_arch=[128, 128]",
            "train.n_envs=4",
            "train.sac.gradient_steps=1",
            "train.sac.learning_rate=1e-3",
        ],
    ),
}
BASE = [
    "actions.mode=rates",
    "train.algo=SAC",
    "train.n_envs=1",
    "train.sac.net_arch=[256, 256]",
    "train.sac.batch_size=256",
    "evaluate.periodic_episodes=10",
    "train.checkpoint_every=25000",
    "evaluate.record_episodes=3",
    "evaluate.image_every=0",
]


def run(args) -> None:
    """Train every (schedule, seed) asked for, one after another."""
    from fastrl.runner import start_run

    for seed in args.seeds:
        for name in args.schedules:
            sets = [
                *BASE,
                *SCHEDULES[name][1],
                f"train.seed={seed}",
                f"train.timesteps={args.steps}",
                f"evaluate.periodic_every={args.eval_every}",
                f"train.sac.periodic_every={args.eval_every}",
            ]
            t0 = time.perf_counter()
            path = start_run("specs/tracelines.yaml", sets, Path(args.root) / name, progress=not args.quiet)
            print(f"{name} seed {seed}: {path} in {time.perf_counter() - t0:.0f} s", flush=True)


def summarise(run_dir: Path) -> dict:
    """Final evaluation, speed and learning curve of one run."""
    ev = json.loads((run_dir / "eval.json").read_text())
    meta = json.loads((run_dir / "meta.json").read_text())
    steps, subs, _ = eval_curve(run_dir)
    return {
        "run": str(run_dir),
        "final_subtasks": ev["agent"]["subtasks_completed"],
        "final_success": ev["agent"]["success_rate"],
        "expert_subtasks": ev["expert"]["subtasks_completed"],
        "train_fps": meta["train_fps"],
        "train_minutes": meta["timesteps"] / meta["train_fps"] / 60,
        "curve": {"steps": steps, "subtasks": subs},
    }


def report(args) -> None:
    """Table over seeds per schedule, and the figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    print(f"# machine: {machine_line()}; root {args.root}")
    print(
        "| schedule | what | seeds | final subtasks | final success | train steps/s | train wall time | speed vs sb3 |"
    )
    print("|---|---|---|---|---|---|---|---|")
    fig, ax = plt.subplots(figsize=(7, 4.2))
    rows, ref_fps = {}, None
    for name, (what, _) in SCHEDULES.items():
        runs = [summarise(p.parent) for p in sorted((Path(args.root) / name).rglob("eval.json"))]
        if not runs:
            continue
        rows[name] = runs
        fps = float(np.mean([r["train_fps"] for r in runs]))
        ref_fps = fps if name == "sb3" else ref_fps
        finals = [r["final_subtasks"] for r in runs]
        speed = f"{fps / ref_fps:.1f}x" if ref_fps else "-"
        print(
            f"| {name} | {what} | {len(runs)} | {np.mean(finals):.1%} ± {np.std(finals):.1%} | "
            f"{np.mean([r['final_success'] for r in runs]):.0%} | {fps:.0f} | "
            f"{np.mean([r['train_minutes'] for r in runs]):.1f} min | {speed} |"
        )
        plot_mean_range(
            ax,
            [(r["curve"]["steps"], r["curve"]["subtasks"]) for r in runs],
            f"{name} (n={len(runs)}, {fps:.0f} steps/s)",
            alpha=0.12,
        )
    label_curve_axes(ax, "SAC on TraceLines (rates): update schedules, mean and range over seeds")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, args.figure, rows)


def main() -> None:
    """Parse arguments and run or report."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("command", choices=["run", "report"])
    ap.add_argument("--schedules", nargs="+", default=list(SCHEDULES), choices=list(SCHEDULES))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--eval-every", type=int, default=10_000)
    ap.add_argument("--root", default="runs/bench-sac")
    ap.add_argument("--figure", default="docs/sac_schedules.png")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args()
    run(args) if args.command == "run" else report(args)


if __name__ == "__main__":
    main()
