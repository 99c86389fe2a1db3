"""How much faster a sweep on Ray Tune finishes than the same runs one after another, on this machine.

    python bench/sweep_speedup.py                         # 3 learning rates x 3 seeds of 20k-step TraceLines
    python bench/sweep_speedup.py --timesteps 5000 --json runs/bench/sweep_speedup.json

Both halves run the same 9 ordinary runs (`start_run`, the spec's evaluation and recording included) in the
same process invocation: first one after another in this process with torch's default threads (what a bench
script's loop does), then as `fastrl sweep` does it (a local Ray, one CPU and one torch thread per trial).
It prints both wall times, their ratio, the machine and its load before and after: run it on a quiet machine.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("CI", "1")

import argparse
import io
import json
import platform
import shutil
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

from rich.console import Console

from fastrl.runner import start_run
from fastrl.runner.sweep import create_sweep, run_sweep, trial_overrides
from fastrl.runner.sweep_table import summarize

SPEC = Path(__file__).resolve().parent.parent / "specs" / "tracelines.yaml"


def machine() -> dict:
    """CPU, cores and load average now."""
    return {
        "cpu": platform.processor() or platform.machine(),
        "cores": os.cpu_count(),
        "load_avg": [round(x, 2) for x in os.getloadavg()],
        "utc": datetime.now(UTC).isoformat(timespec="seconds"),
    }


def serial(folder: Path, manifest: dict) -> tuple[float, list[float]]:
    """The sweep's trials as ordinary runs one after another in this process; wall seconds, total and per run."""
    quiet = Console(file=io.StringIO())
    t0, each = time.perf_counter(), []
    for trial in manifest["trials"]:
        t1 = time.perf_counter()
        start_run(
            folder / "spec.yaml", trial_overrides(trial), console=quiet, progress=False, into=folder / trial["name"]
        )
        each.append(time.perf_counter() - t1)
    return time.perf_counter() - t0, each


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--timesteps", type=int, default=20_000)
    ap.add_argument("--values", default="1e-4,3e-4,1e-3", help="train.ppo.learning_rate values")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--json", type=Path, help="write the figures here")
    args = ap.parse_args()

    grid = {"train.ppo.learning_rate": args.values.split(",")}
    seeds = [int(s) for s in args.seeds.split(",")]
    base = [f"train.timesteps={args.timesteps}"]
    root = Path(tempfile.mkdtemp(prefix="sweep_speedup-"))
    try:
        before = machine()
        print(f"machine: {before['cpu']}, {before['cores']} cores, load average {before['load_avg']}", flush=True)
        one_by_one = create_sweep(SPEC, base, grid, seeds, 1, root / "serial")
        t_serial, serial_each = serial(one_by_one, json.loads((one_by_one / "sweep.json").read_text()))
        print(f"one after another: {t_serial:.1f} s", flush=True)
        swept = create_sweep(SPEC, base, grid, seeds, 1, root / "sweep")
        t0 = time.perf_counter()
        failed = run_sweep(swept, None, Console(file=io.StringIO()))
        t_sweep = time.perf_counter() - t0
        after = machine()
        n = len(json.loads((swept / "sweep.json").read_text())["trials"])
        done = sum(r["seeds"] for r in summarize(swept)["rows"])
        print(f"fastrl sweep (Ray Tune, 1 CPU per trial): {t_sweep:.1f} s  ({done}/{n} trials finished)")
        print(f"speed-up: {t_serial / t_sweep:.2f}x  (load average after: {after['load_avg']})")
        sweep_each = [t["wall_s"] for t in summarize(swept)["trials"] if t.get("wall_s") is not None]
        alone, inside = sum(serial_each) / len(serial_each), sum(sweep_each) / max(len(sweep_each), 1)
        print(f"per run: {alone:.1f} s one after another, {inside:.1f} s inside the sweep (two at a time)")
        result = {
            "runs": n,
            "grid": grid,
            "seeds": seeds,
            "timesteps": args.timesteps,
            "serial_s": t_serial,
            "sweep_s": t_sweep,
            "speedup": t_serial / t_sweep,
            "serial_run_s": serial_each,
            "sweep_trial_s": sweep_each,
            "failed": failed,
            "machine_before": before,
            "machine_after": after,
            "python": platform.python_version(),
        }
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(result, indent=2))
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
