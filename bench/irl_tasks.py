"""GAIL, AIRL (PPO generator) and BC from 20 scripted-expert demonstrations, next to PPO on the heuristic reward.

    python bench/irl_tasks.py run --tasks tracelines --algos gail airl ppo     # train (real `fastrl run`s)
    python bench/irl_tasks.py report                                          # table + figure from the runs

Every run is a real run directory under --root (default runs/bench-irl) with periodic deterministic evaluation
(10 seeds every 50k steps), a 3M-step cap, and early stop once an evaluation completes every subtask. The report
gives, per task and algorithm: steps and wall time until an evaluation reached 90% of the expert's subtask
completion, the final evaluation on 20 seeds, and a figure of evaluation subtasks over steps (the paper's Fig. 4).
Run two processes at once on a 2-core machine (e.g. split by task); each run uses one core.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import platform
import time
from pathlib import Path

TASKS = ["imagecentring", "periscoping", "tracelines"]
ALGOS = ["ppo", "gail", "airl", "bc"]


def overrides(algo: str, seed: int, cap: int) -> list[str]:
    """The spec changes of one benchmark run."""
    out = [
        f"train.timesteps={cap}",
        f"train.seed={seed}",
        "evaluate.periodic_every=50000",
        "evaluate.periodic_episodes=10",
        "evaluate.stop_at_subtasks=1.0",
        "train.checkpoint_every=50000",
        "train.keep_checkpoints=100",
        "evaluate.image_every=8",
        "evaluate.record_episodes=5",
    ]
    return out + ([f"irl.algorithm={algo}"] if algo != "ppo" else [])


def run(args) -> None:
    """Train every (task, algorithm) asked for, one after another."""
    from fastrl.runner import start_run

    for task in args.tasks:
        for algo in args.algos:
            t0 = time.perf_counter()
            changes = overrides(algo, args.seed, args.cap) + (args.set if algo in ("gail", "airl") else [])
            path = start_run(Path("specs") / f"{task}.yaml", changes, args.root, progress=not args.quiet)
            print(f"{task} {algo}: {path} in {time.perf_counter() - t0:.0f} s", flush=True)


def curve(run_dir: Path) -> tuple[list[int], list[float], list[float]]:
    """(timesteps, evaluation subtasks, wall seconds) of a run's periodic evaluations."""
    steps, subtasks, fps_time = [], [], []
    for line in (run_dir / "metrics.jsonl").read_text().splitlines():
        row = json.loads(line)
        if "eval/subtasks" in row:
            steps.append(row["timesteps"])
            subtasks.append(row["eval/subtasks"])
            fps_time.append(row["timesteps"] / max(row["fps"], 1e-9))
    return steps, subtasks, fps_time


def plot_mean_range(ax, curves: list[tuple[list[int], list[float]]], label: str, alpha: float = 0.15) -> None:
    """Mean and min-max band of evaluation curves over seeds (cut to the shortest), starting at (0, 0)."""
    import numpy as np

    n = min(len(c[0]) for c in curves)
    steps = [0, *curves[0][0][:n]]
    subs = np.array([[0, *c[1][:n]] for c in curves])
    (line,) = ax.plot(steps, subs.mean(0), label=label)
    ax.fill_between(steps, subs.min(0), subs.max(0), color=line.get_color(), alpha=alpha)


def save_figure(fig, path: str, rows) -> None:
    """The figure as PNG and its data as JSON beside it."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    out.with_suffix(".json").write_text(json.dumps(rows, indent=2))
    print(f"figure: {out}")


def algo_of(run_dir: Path) -> str:
    """ppo, gail or airl, from the run directory name."""
    name = run_dir.name.split("-", 1)[1]
    return name.split("-")[0]


def report(args) -> None:
    """Print the table and write the figure and JSON."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    present = [task for task in TASKS if any((Path(args.root) / task).glob("*/eval.json"))]
    if not present:
        raise SystemExit(f"no finished runs under {args.root}")
    rows, fig = [], plt.figure(figsize=(4.4 * len(present), 3.8))
    print(
        f"# machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"{platform.python_version()}; root {args.root}"
    )
    print(
        "| task | algorithm | steps to 90% of expert | wall time to 90% | steps trained | train time | "
        "final success | final subtasks (expert) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for k, task in enumerate(present):  # a panel per task that has runs
        ax = fig.add_subplot(1, len(present), k + 1)
        runs = sorted(
            (f.parent for f in (Path(args.root) / task).glob("*/eval.json")),
            key=lambda d: (ALGOS.index(algo_of(d)), d.name),
        )  # same order and colours in every panel
        for run_dir in runs:
            algo = algo_of(run_dir)
            meta = json.loads((run_dir / "meta.json").read_text())
            ev = json.loads((run_dir / "eval.json").read_text())
            steps, subs, secs = curve(run_dir) if algo != "bc" else ([], [], [])  # BC trains offline: no curve
            expert = ev["expert"]["subtasks_completed"]
            hit = next((i for i, s in enumerate(subs) if s >= 0.9 * expert), None)
            row = {
                "task": task,
                "algo": algo,
                "run": str(run_dir),
                "expert_subtasks": expert,
                "steps_to_90": steps[hit] if hit is not None else None,
                "seconds_to_90": secs[hit] if hit is not None else None,
                "steps": meta["trained_timesteps"],
                "train_seconds": meta["train_seconds"],
                "final_success": ev["agent"]["success_rate"],
                "final_subtasks": ev["agent"]["subtasks_completed"],
            }
            rows.append(row)
            to90 = f"{row['steps_to_90']:,}" if hit is not None else "not reached"
            if algo == "bc":  # trained offline on the demonstrations: no environment steps
                to90 = "0 (offline)" if row["final_subtasks"] >= 0.9 * expert else "not reached"
            wall = f"{row['seconds_to_90'] / 60:.1f} min" if hit is not None else "-"
            print(
                f"| {task} | {algo.upper()} | {to90} | {wall} | {row['steps']:,} | "
                f"{row['train_seconds'] / 60:.1f} min | {row['final_success']:.0%} | "
                f"{row['final_subtasks']:.1%} ({expert:.0%}) |"
            )
            if algo == "bc":  # no training loop: its final evaluation, as a level
                ax.axhline(row["final_subtasks"], color="black", ls="--", lw=1, label="BC (20 demos)")
            else:
                seen = algo.upper() in ax.get_legend_handles_labels()[1]  # one legend entry per algorithm
                ax.plot(
                    [0, *steps],
                    [0, *subs],
                    marker=".",
                    label=None if seen else algo.upper(),
                    color=f"C{ALGOS.index(algo)}",
                )
        ax.axhline(0.9, color="grey", ls=":", lw=1)
        ax.set(title=task, xlabel="environment steps", ylabel="subtasks completed (10 eval seeds)", ylim=(-0.02, 1.02))
        ax.xaxis.set_major_formatter(lambda x, _: f"{x / 1e6:g}M" if x >= 1e6 else f"{x / 1e3:g}k" if x else "0")
        ax.legend()
    fig.tight_layout()
    out = Path(args.figure)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    (out.with_suffix(".json")).write_text(json.dumps(rows, indent=2))
    print(f"figure: {out}")


def main() -> None:
    """Parse arguments and run or report."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["run", "report"])
    ap.add_argument("--tasks", nargs="+", default=TASKS, choices=TASKS)
    ap.add_argument("--algos", nargs="+", default=ALGOS, choices=ALGOS)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cap", type=int, default=3_000_000, help="step budget per run")
    ap.add_argument("--root", default="runs/bench-irl")
    ap.add_argument(
        "--figure",
        help="default: docs/irl_fig4.png for the default root, else ROOT/fig4.png (so a "
        "report on a probe's root leaves the published figure alone)",
    )
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    ap.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="spec overrides for the GAIL and AIRL runs, e.g. irl.discriminator.history=200000",
    )
    args = ap.parse_args()
    if args.figure is None:
        default_root = Path(args.root) == Path(ap.get_default("root"))
        args.figure = "docs/irl_fig4.png" if default_root else str(Path(args.root) / "fig4.png")
    run(args) if args.mode == "run" else report(args)


if __name__ == "__main__":
    main()
