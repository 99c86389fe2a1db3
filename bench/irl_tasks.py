"""GAIL, AIRL (PPO generator) and BC from 20 scripted-expert demonstrations, next to PPO on the heuristic reward.

    python bench/irl_tasks.py run --tasks tracelines --algos gail airl ppo --seeds 0 1 2  # a `fastrl sweep` per task
    python bench/irl_tasks.py report                                          # table + figure from the runs

`run` makes one sweep per task (fastrl.runner.sweep.plan, on Ray Tune: a local Ray, or a cluster with --address) whose
configurations are the algorithms and whose trials are algorithm x seed, each a real run directory under
ROOT/TASK/<time>-sweep/ with periodic deterministic evaluation (10 seeds every 50k steps), a 3M-step cap, and early
stop once an evaluation completes every subtask; --cpus-per-trial CPUs (and torch threads) each, so a 2-core machine
runs two at once. An interrupted sweep continues with `fastrl sweep --resume ROOT/TASK/<time>-sweep`. The report
reads every run under ROOT/TASK (sweep trials and the older run directories alike) and gives, per task and
algorithm: steps and wall time until an evaluation reached 90% of the expert's subtask completion, the final
evaluation on 20 seeds, and a figure of evaluation subtasks over steps (the paper's Fig. 4).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
from pathlib import Path

from common import eval_curve, figure_path, finished_runs, first_at, label_curve_axes, machine_line, save_figure, sweep

TASKS = ["imagecentring", "periscoping", "tracelines"]
ALGOS = ["ppo", "gail", "airl", "bc"]


IRL_ALGORITHM = {"ppo": "none", "gail": "gail", "airl": "airl", "bc": "bc"}  # irl.algorithm of each


def overrides(cap: int) -> list[str]:
    """The spec changes every benchmark run shares."""
    return [
        f"train.timesteps={cap}",
        f"evaluate.periodic_every={min(50000, cap)}",
        "evaluate.periodic_episodes=10",
        "evaluate.stop_at_subtasks=1.0",
        f"train.checkpoint_every={min(50000, cap)}",
        "train.keep_checkpoints=100",
        "evaluate.image_every=8",
        "evaluate.record_episodes=5",
    ]


def run(args) -> None:
    """A sweep per task: the algorithms asked for x the seeds, each trial an ordinary run."""
    from datetime import UTC, datetime

    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
    settings = [{"irl.algorithm": IRL_ALGORITHM[a]} for a in args.algos]
    for task in args.tasks:
        folder = Path(args.root) / task / f"{stamp}-sweep"
        spec = Path("specs") / f"{task}.yaml"
        sweep(
            spec,
            overrides(args.cap) + args.set,
            seeds=args.seeds,
            cpus=args.cpus_per_trial,
            folder=folder,
            settings=settings,
            address=args.address,
            prefix=f"{task}: ",
        )


def algo_of(run_dir: Path) -> str:
    """ppo, gail, airl or bc, from the run's resolved spec (whatever the directory is called)."""
    import yaml

    irl = yaml.safe_load((run_dir / "spec.yaml").read_text())["irl"]["algorithm"]
    return "ppo" if irl == "none" else irl


def report(args) -> None:
    """Print the table and write the figure and JSON."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    present = [task for task in TASKS if finished_runs(Path(args.root) / task)]
    if not present:
        raise SystemExit(f"no finished runs under {args.root}")
    rows, fig = [], plt.figure(figsize=(4.4 * len(present), 3.8))
    print(f"# machine: {machine_line()}; root {args.root}")
    print(
        "| task | algorithm | steps to 90% of expert | wall time to 90% | steps trained | train time | "
        "final success | final subtasks (expert) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for k, task in enumerate(present):  # a panel per task that has runs
        ax = fig.add_subplot(1, len(present), k + 1)
        runs = sorted(
            finished_runs(Path(args.root) / task), key=lambda d: (ALGOS.index(algo_of(d)), d.name)
        )  # same order and colours in every panel
        for run_dir in runs:
            algo = algo_of(run_dir)
            meta = json.loads((run_dir / "meta.json").read_text())
            ev = json.loads((run_dir / "eval.json").read_text())
            steps, subs, secs = eval_curve(run_dir) if algo != "bc" else ([], [], [])  # BC trains offline: no curve
            expert = ev["expert"]["subtasks_completed"]
            hit = first_at(subs, 0.9 * expert)
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
            label = "BC (20 demos)" if algo == "bc" else algo.upper()
            seen = label in ax.get_legend_handles_labels()[1]  # one legend entry per algorithm
            if algo == "bc":  # no training loop: its final evaluation, as a level
                ax.axhline(row["final_subtasks"], color="black", ls="--", lw=1, label=None if seen else label)
            else:
                ax.plot(
                    [0, *steps],
                    [0, *subs],
                    marker=".",
                    label=None if seen else label,
                    color=f"C{ALGOS.index(algo)}",
                )
        ax.axhline(0.9, color="grey", ls=":", lw=1)
        label_curve_axes(ax, task)
        ax.xaxis.set_major_formatter(lambda x, _: f"{x / 1e6:g}M" if x >= 1e6 else f"{x / 1e3:g}k" if x else "0")
        ax.legend()
    fig.tight_layout()
    save_figure(fig, args.figure, rows)


def main() -> None:
    """Parse arguments and run or report."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["run", "report"])
    ap.add_argument("--tasks", nargs="+", default=TASKS, choices=TASKS)
    ap.add_argument("--algos", nargs="+", default=ALGOS, choices=ALGOS)
    ap.add_argument("--seeds", nargs="+", type=int, default=[0], help="training seeds (each a trial)")
    ap.add_argument("--cap", type=int, default=3_000_000, help="step budget per run")
    ap.add_argument("--root", default="runs/bench-irl")
    ap.add_argument("--address", help="Ray cluster to run on (default: RAY_ADDRESS, else a local Ray)")
    ap.add_argument("--cpus-per-trial", type=int, default=1, help="CPUs and torch threads of each run")
    ap.add_argument(
        "--figure",
        help="default: docs/irl_fig4.png for the default root, else ROOT/fig4.png (so a "
        "report on a probe's root leaves the published figure alone)",
    )
    ap.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="spec overrides for every run, e.g. irl.discriminator.history=200000 (irl.* settings reach the "
        "inverse-RL runs only)",
    )
    args = ap.parse_args()
    if args.figure is None:
        args.figure = figure_path(args.root, ap.get_default("root"), "docs/irl_fig4.png", "fig4.png")
    run(args) if args.mode == "run" else report(args)


if __name__ == "__main__":
    main()
