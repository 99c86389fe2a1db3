"""What the benchmarks share: the machine and its load beside every figure, and the runs' evaluation curves."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


# ---- the machine ---------------------------------------------------------------------------
def cpuinfo(field: str) -> str | None:
    """The first value of a /proc/cpuinfo field (None where there is none)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == field:
                return value.strip()
    except OSError:
        pass
    return None


def cpu_model() -> str:
    """The processor's model name, with its family and model numbers where /proc/cpuinfo has them (a virtual machine
    may name only "AMD EPYC", and two sessions' VMs of that name trained the same spec and seed differently)."""
    name = cpuinfo("model name") or platform.processor() or platform.machine()
    family, model = cpuinfo("cpu family"), cpuinfo("model")
    return f"{name} (family {family}, model {model})" if family and model else name


def versions() -> str:
    """The versions of the packages whose arithmetic the figures rest on."""
    from importlib.metadata import PackageNotFoundError, version

    found = []
    for package in ("mujoco", "numpy", "torch"):
        try:
            found.append(f"{package} {version(package)}")
        except PackageNotFoundError:
            pass
    return ", ".join(found)


def load_figures() -> list[str]:
    """The 1, 5 and 15-minute load averages, written as /proc/loadavg writes them."""
    return [f"{x:.2f}" for x in os.getloadavg()]


def load_average() -> str:
    """The three load averages now, on one line."""
    return " ".join(load_figures())


def load_after() -> str:
    """The line that closes a report: the load average at its end."""
    return f"load average after: {load_average()}"


def machine_line() -> str:
    """One line naming the machine, its cores, the load now and the versions that set the arithmetic."""
    cores = f"{os.cpu_count()} cores, load average {load_average()}"
    return f"{cpu_model()}, {cores}, Python {platform.python_version()}, {versions()}"


def utc_stamp() -> str:
    """The UTC date and time now, ISO 8601 to the second."""
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


def git_commit() -> str | None:
    """The checkout's short commit (None outside one)."""
    try:
        run = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], check=False, cwd=ROOT, text=True, capture_output=True, timeout=5
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return run.stdout.strip() or None


# ---- runs and their evaluation curves ------------------------------------------------------
def eval_curve(run_dir: Path) -> tuple[list[int], list[float], list[float]]:
    """(timesteps, evaluation subtasks, training seconds) of a run's periodic evaluations, from metrics.jsonl."""
    steps, subtasks, seconds = [], [], []
    for line in (Path(run_dir) / "metrics.jsonl").read_text().splitlines():
        row = json.loads(line)
        if "eval/subtasks" in row:
            steps.append(row["timesteps"])
            subtasks.append(row["eval/subtasks"])
            seconds.append(row["timesteps"] / max(row["fps"], 1e-9))
    return steps, subtasks, seconds


def first_at(values: list[float], level: float) -> int | None:
    """The index of the first value at or above level (None if none is)."""
    return next((i for i, v in enumerate(values) if v >= level), None)


def finished_runs(folder: Path) -> list[Path]:
    """Every finished run directory under a folder: a sweep's trials and older runs made one by one."""
    return sorted(f.parent for f in Path(folder).rglob("eval.json") if (f.parent / "meta.json").exists())


def sweep(
    spec: Path, overrides: list[str], *, seeds, cpus: int, folder: Path, settings, address, prefix: str = ""
) -> None:
    """One `fastrl sweep` (settings x seeds, each trial an ordinary run), its results written and failures said."""
    from fastrl.runner.sweep.plan import create_sweep
    from fastrl.runner.sweep.table import write_results
    from fastrl.runner.sweep.tune import run_sweep

    t0 = time.perf_counter()
    create_sweep(spec, overrides, {}, seeds, cpus, folder, settings)
    failed = run_sweep(folder, address)
    write_results(folder, failed)
    print(f"{prefix}{folder} in {time.perf_counter() - t0:.0f} s, {len(failed)} failed", flush=True)
    for f in failed:
        print(f"  {f['trial']} failed twice: {f['error']}", flush=True)


# ---- figures -------------------------------------------------------------------------------
def figure_path(root: str, default_root: str, published: str, name: str) -> str:
    """The published figure for the default root, else one in the root (a probe's report leaves it alone)."""
    return published if Path(root) == Path(default_root) else str(Path(root) / name)


def plot_mean_range(ax, curves: list[tuple[list[int], list[float]]], label: str, alpha: float = 0.15) -> None:
    """Mean and min-max band of evaluation curves over seeds (cut to the shortest), starting at (0, 0)."""
    import numpy as np

    n = min(len(c[0]) for c in curves)
    steps = [0, *curves[0][0][:n]]
    subs = np.array([[0, *c[1][:n]] for c in curves])
    (line,) = ax.plot(steps, subs.mean(0), label=label)
    ax.fill_between(steps, subs.min(0), subs.max(0), color=line.get_color(), alpha=alpha)


def label_curve_axes(ax, title: str) -> None:
    """Title and labels of an evaluation-curve panel: subtasks over environment steps."""
    ax.set(title=title, xlabel="environment steps", ylabel="subtasks completed (10 eval seeds)", ylim=(-0.02, 1.02))


def save_figure(fig, path: str, rows) -> None:
    """The figure as PNG and its data as JSON beside it."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    out.with_suffix(".json").write_text(json.dumps(rows, indent=2))
    print(f"figure: {out}")
