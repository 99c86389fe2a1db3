"""How much faster a sweep on Ray Tune finishes than the same runs one after another, on this machine.

    python bench/sweep_speedup.py                         # 3 learning rates x 3 seeds of 20k-step TraceLines
    python bench/sweep_speedup.py --timesteps 5000 --json runs/bench/sweep_speedup.json

Three timings of the same 9 ordinary runs (`start_run`, the spec's evaluation and recording included) in one
process invocation: one after another in this process as `fastrl run` does them (torch's default threads, the
spec's `train.workers`: both cores); one after another kept to one CPU each (one torch thread, one env process:
what a sweep trial is); then as `fastrl sweep` does it (a local Ray, one CPU and one torch thread per trial).
It prints the wall times, the ratios, the cores each half kept busy on average (machine-wide, from /proc/stat)
and so the ceiling a sweep on this machine has (cores / the cores a run one after another keeps busy), the
machine and its load before and after: run it on a quiet machine.
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
from pathlib import Path

import torch
from common import cpu_model, load_average, load_figures, machine_line, utc_stamp
from rich.console import Console

from fastrl.runner import start_run
from fastrl.runner.sweep.plan import create_sweep, trial_overrides
from fastrl.runner.sweep.table import summarize
from fastrl.runner.sweep.tune import run_sweep

SPEC = Path(__file__).resolve().parent.parent / "specs" / "tracelines.yaml"


def machine() -> dict:
    """CPU, cores and load average now."""
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "load_avg": [float(x) for x in load_figures()],
        "utc": utc_stamp(),
    }


def busy_seconds() -> float | None:
    """CPU seconds all cores of this machine have spent busy since boot (Linux /proc/stat), else None."""
    try:
        fields = Path("/proc/stat").read_text().splitlines()[0].split()[1:]
    except OSError:
        return None
    user, nice, system, _idle, _iowait, irq, softirq, steal = (int(x) for x in fields[:8])
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


def cores_busy(busy0: float | None, seconds: float) -> float | None:
    """Cores kept busy on average since `busy0` over `seconds` of wall time."""
    busy1 = busy_seconds()
    return None if busy0 is None or busy1 is None else round((busy1 - busy0) / seconds, 2)


def serial(folder: Path, manifest: dict, one_cpu: bool) -> tuple[float, list[float]]:
    """The sweep's trials as ordinary runs one after another in this process; wall seconds, total and per run."""
    quiet, threads = Console(file=io.StringIO()), torch.get_num_threads()
    extra = ["train.workers=1"] if one_cpu else []
    torch.set_num_threads(1 if one_cpu else threads)
    t0, each = time.perf_counter(), []
    try:
        for trial in manifest["trials"]:
            t1 = time.perf_counter()
            overrides = [*trial_overrides(trial), *extra]
            start_run(folder / "spec.yaml", overrides, console=quiet, progress=False, into=folder / trial["name"])
            each.append(time.perf_counter() - t1)
    finally:
        torch.set_num_threads(threads)
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
        print(f"machine: {machine_line()}", flush=True)
        halves = {}
        for name, one_cpu in (("serial", False), ("serial_one_cpu", True)):
            folder = create_sweep(SPEC, base, grid, seeds, 1, root / name)
            busy0 = busy_seconds()
            wall, each = serial(folder, json.loads((folder / "sweep.json").read_text()), one_cpu)
            halves[name] = {"s": wall, "run_s": each, "cores_busy": cores_busy(busy0, wall)}
            how = "kept to one CPU each" if one_cpu else "as fastrl run does them"
            print(f"one after another, {how}: {wall:.1f} s, cores busy {halves[name]['cores_busy']}", flush=True)
        swept = create_sweep(SPEC, base, grid, seeds, 1, root / "sweep")
        busy0, t0 = busy_seconds(), time.perf_counter()
        failed = run_sweep(swept, None, Console(file=io.StringIO()))
        t_sweep = time.perf_counter() - t0
        sweep_busy = cores_busy(busy0, t_sweep)
        after = machine()
        n = len(json.loads((swept / "sweep.json").read_text())["trials"])
        done = sum(r["seeds"] for r in summarize(swept)["rows"])
        t_serial, t_one = halves["serial"]["s"], halves["serial_one_cpu"]["s"]
        print(f"fastrl sweep (Ray Tune, 1 CPU per trial): {t_sweep:.1f} s, cores busy {sweep_busy} ({done}/{n} trials)")
        print(f"speed-up: {t_serial / t_sweep:.2f}x over runs as fastrl run does (load after: {load_average()})")
        print(f"          {t_one / t_sweep:.2f}x over the same runs kept to one CPU each")
        busy = halves["serial"]["cores_busy"]
        ceiling = (os.cpu_count() or 1) / busy if busy else None
        if ceiling:
            print(f"ceiling on this machine: {ceiling:.2f}x (its {os.cpu_count()} cores / the {busy} a run keeps busy)")
        sweep_each = [t["wall_s"] for t in summarize(swept)["trials"] if t.get("wall_s") is not None]
        mean = lambda xs: sum(xs) / max(len(xs), 1)  # noqa: E731
        print(
            f"per run: {mean(halves['serial']['run_s']):.1f} s as fastrl run does them, "
            f"{mean(halves['serial_one_cpu']['run_s']):.1f} s on one CPU, {mean(sweep_each):.1f} s inside the sweep"
        )
        result = {
            "runs": n,
            "grid": grid,
            "seeds": seeds,
            "timesteps": args.timesteps,
            "serial_s": t_serial,
            "serial_one_cpu_s": t_one,
            "sweep_s": t_sweep,
            "speedup": t_serial / t_sweep,
            "speedup_over_one_cpu": t_one / t_sweep,
            "ceiling": ceiling,
            "serial_run_s": halves["serial"]["run_s"],
            "serial_one_cpu_run_s": halves["serial_one_cpu"]["run_s"],
            "sweep_trial_s": sweep_each,
            "cores_busy": {
                "serial": busy,
                "serial_one_cpu": halves["serial_one_cpu"]["cores_busy"],
                "sweep": sweep_busy,
            },
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
