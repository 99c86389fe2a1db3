"""Off-policy AIRL (SAC generator) on TraceLines: both additions, and each one ablated, over seeds (Fig. 5).

    python bench/irl_offpolicy.py run --seeds 0 1 2 --variants full no-current-rollout no-spectral-norm
    python bench/irl_offpolicy.py report

Variants: `full` (spectral normalisation + discriminator trained on the current rollout only),
`no-current-rollout` (spectral norm, discriminator trained on samples of the whole replay buffer),
`no-spectral-norm` (current rollout, plain discriminator). `run` is one sweep (fastrl.runner.sweep.plan, on Ray Tune:
a local Ray, or a cluster with --address) whose configurations are the variants and whose trials are variant x
seed, each a real run directory under ROOT/<time>-sweep/ with a deterministic evaluation on 10 seeds every
--eval-every steps, the same budget for all (a run stops at its first evaluation at >= 95% of subtasks, the
spec's `evaluate.stop_at_subtasks`); --cpus-per-trial CPUs (and torch threads) each. An
interrupted sweep continues with `fastrl sweep --resume ROOT/<time>-sweep`. The report reads every run under
ROOT (sweep trials and the older ROOT/VARIANT/tracelines/* runs alike; the variant from each run's spec) and
prints a table (mean and spread over seeds of the final evaluation, steps to 90% of the expert) and writes a
figure of subtasks completed over steps. The defaults are those of docs/irl_fig5.png (rates actions, 60k steps,
4 envs with one update per 4 steps); `--mode continuous --schedule 8x32 --steps 100000 --eval-every 25000 --root
runs/bench-offpolicy` gave docs/irl_fig5_continuous.png. `--schedule spec` trains the generator with the FAST
specs' SAC settings (32 envs, 8 updates per 32 steps).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
from pathlib import Path

import numpy as np
from common import (
    eval_curve,
    figure_path,
    finished_runs,
    label_curve_axes,
    machine_line,
    plot_mean_range,
    save_figure,
    sweep,
)

VARIANTS = {
    "full": ["irl.discriminator.spectral_norm=true", "irl.discriminator.current_rollout=true"],
    "no-current-rollout": ["irl.discriminator.spectral_norm=true", "irl.discriminator.current_rollout=false"],
    "no-spectral-norm": ["irl.discriminator.spectral_norm=false", "irl.discriminator.current_rollout=true"],
}
COMMON = [
    "train.algo=SAC",
    "train.sac.net_arch=[128, 128]",
    "train.sac.batch_size=256",
    "train.sac.learning_starts=5000",
    "irl.algorithm=airl",
    "irl.discriminator.steps=16",
    "irl.discriminator.learning_rate=1e-3",
    "evaluate.periodic_episodes=10",
    "train.checkpoint_every=50000",
    "train.keep_checkpoints=100",
    "evaluate.record_episodes=5",
]
SCHEDULES = {  # SAC schedules of bench/sac_speed.py
    # 8 envs, 32 steps each between 32 updates (1 update per 8 steps); the discriminator fits after every rollout
    "8x32": ["train.n_envs=8", "train.sac.train_freq=32", "train.sac.gradient_steps=32"],
    # stable-baselines3's own SAC and schedule (1 env, 1 update per step, [256, 256]), the same discriminator work
    "sb3": [
        "train.n_envs=1",
        "train.sac.train_freq=1",
        "train.sac.gradient_steps=1",
        "train.sac.net_arch=[256, 256]",
        "train.sac.lean_update=false",
        "irl.discriminator.every=256",
    ],
    # the FAST specs' SAC (32 envs, 8 updates per 32 steps, bench/time_to_solve.py --algo SAC); the discriminator
    # fits every 256 steps on the samples since its last fit
    "spec": ["train.sac.gradient_steps=8", "irl.discriminator.every=256"],
    # 4 envs, 1 update per 4 steps; the discriminator fits every 256 steps on the samples since its last fit
    "4env-quarter": [
        "train.n_envs=4",
        "train.sac.train_freq=1",
        "train.sac.gradient_steps=1",
        "irl.discriminator.every=256",
    ],
}


def run(args) -> None:
    """One sweep: the variants asked for x the seeds, each trial an ordinary run."""
    from datetime import UTC, datetime

    base = [
        *COMMON,
        *SCHEDULES[args.schedule],
        f"actions.mode={args.mode}",
        f"train.timesteps={args.steps}",
        f"evaluate.periodic_every={args.eval_every}",
        f"train.sac.periodic_every={args.eval_every}",
        *args.set,
    ]
    settings = [dict(kv.split("=", 1) for kv in VARIANTS[v]) for v in args.variants]
    folder = Path(args.root) / f"{datetime.now(UTC).strftime('%Y%m%dT%H%M%SZ')}-sweep"
    spec, cpus = Path("specs/tracelines.yaml"), args.cpus_per_trial
    sweep(spec, base, seeds=args.seeds, cpus=cpus, folder=folder, settings=settings, address=args.address)


def variant_of(run_dir: Path) -> str | None:
    """The variant a run trained, from its resolved spec (None if it is none of them)."""
    import yaml

    disc = yaml.safe_load((run_dir / "spec.yaml").read_text())["irl"]["discriminator"]
    mine = {f"irl.discriminator.{k}={str(disc[k]).lower()}" for k in ("spectral_norm", "current_rollout")}
    return next((v for v, sets in VARIANTS.items() if set(sets) == mine), None)


def report(args) -> None:
    """Table over seeds per variant, and the figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    print(f"# machine: {machine_line()}; root {args.root}")
    print("| variant | seeds | final subtasks, mean ± sd | final success | steps to 90% (per seed) | train steps/s |")
    print("|---|---|---|---|---|---|")
    fig, ax = plt.subplots(figsize=(7, 4.2))
    rows = []
    found = finished_runs(Path(args.root))
    for variant in VARIANTS:
        runs = [r for r in found if variant_of(r) == variant]
        if not runs:
            continue
        finals, success, to90, fps, curves = [], [], [], [], []
        for run_dir in runs:
            ev = json.loads((run_dir / "eval.json").read_text())
            meta = json.loads((run_dir / "meta.json").read_text())
            steps, subs, _ = eval_curve(run_dir)
            finals.append(ev["agent"]["subtasks_completed"])
            success.append(ev["agent"]["success_rate"])
            hit = next((s for s, v in zip(steps, subs) if v >= 0.9 * ev["expert"]["subtasks_completed"]), None)
            to90.append(hit)
            fps.append(meta["train_fps"])
            curves.append((steps, subs))
            rows.append(
                {
                    "variant": variant,
                    "run": str(run_dir),
                    "final_subtasks": finals[-1],
                    "final_success": success[-1],
                    "steps_to_90": hit,
                    "train_fps": fps[-1],
                    "curve": {"steps": steps, "subtasks": subs},
                }
            )
        plot_mean_range(ax, curves, f"{variant} (n={len(runs)})")
        hits = ", ".join(f"{h:,}" if h else "-" for h in to90)
        print(
            f"| {variant} | {len(runs)} | {np.mean(finals):.1%} ± {np.std(finals):.1%} | {np.mean(success):.0%} | "
            f"{hits} | {np.mean(fps):.0f} |"
        )
    ax.axhline(0.9, color="grey", ls=":", lw=1)
    label_curve_axes(ax, "Off-policy AIRL (SAC) on TraceLines: mean and range over seeds")
    ax.legend()
    fig.tight_layout()
    save_figure(fig, args.figure, rows)


def main() -> None:
    """Parse arguments and run or report."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("command", choices=["run", "report"])
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--steps", type=int, default=60_000)
    ap.add_argument(
        "--mode",
        default="rates",
        choices=["rates", "continuous"],
        help="action mode: rates (5 portal rates, first order) or continuous (7 tip accelerations)",
    )
    ap.add_argument("--schedule", default="4env-quarter", choices=list(SCHEDULES), help="SAC update schedule")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="more spec overrides")
    ap.add_argument("--eval-every", type=int, default=10_000, help="steps between evaluations during training")
    ap.add_argument("--root", default="runs/bench-offpolicy-rates")
    ap.add_argument(
        "--figure",
        help="default: docs/irl_fig5.png for the default root, else ROOT/fig5.png (so a report on a probe's root "
        "leaves the published figure alone)",
    )
    ap.add_argument("--address", help="Ray cluster to run on (default: RAY_ADDRESS, else a local Ray)")
    ap.add_argument("--cpus-per-trial", type=int, default=1, help="CPUs and torch threads of each run")
    args = ap.parse_args()
    if args.figure is None:
        args.figure = figure_path(args.root, ap.get_default("root"), "docs/irl_fig5.png", "fig5.png")
    run(args) if args.command == "run" else report(args)


if __name__ == "__main__":
    main()
