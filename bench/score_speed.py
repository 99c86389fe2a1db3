"""How long the whole `fastrl score` command takes on 100 trajectories, start-up, figures and recording included.

    python bench/score_speed.py                                  # makes an AIRL run and a 5 x 20 TraceLines cohort
    python bench/score_speed.py --run RUN_DIR --trajectories DIR --repeats 7

Without --run, a small AIRL run of TraceLines (`fastrl irl ... --timesteps 4096`; the cost of scoring does not
depend on how well it learned) is made under runs/bench-score; without --trajectories, a synthetic cohort
(`fastrl cohort --levels 5 --per-level 20`). Each repeat runs `python -m fastrl.cli score DIR --run RUN` as a
subprocess and times it from launch to exit; the first run fills the run's caches (reference scores, the scripted
expert's paths per seed) and is reported apart as the cold run. Prints the machine and its load, the median, best and
worst warm wall times, the CPU time of the command (both processes), and the breakdown: Python with fastrl's imports,
loading the run, scoring (replay and networks), the report, and figures + recording (from scores.json's seconds).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path("runs/bench-score")


def machine() -> str:
    """CPU model, cores and the load averages now."""
    model = platform.processor() or "?"
    try:
        model = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return f"{model}, {os.cpu_count()} cores, load average {load}, Python {platform.python_version()}"


def fastrl(*args: str) -> subprocess.CompletedProcess:
    """`python -m fastrl.cli ARGS` with this environment; stops the bench on failure."""
    res = subprocess.run([sys.executable, "-m", "fastrl.cli", *args], capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"fastrl {' '.join(args)} failed:\n{res.stdout}\n{res.stderr}")
    return res


def make_run(root: Path) -> Path:
    """A small AIRL run of TraceLines (made once)."""
    runs = sorted((root / "runs" / "tracelines").glob("*-airl-*"))
    if not runs:
        fastrl(
            "irl", "specs/tracelines.yaml", "--algorithm", "airl", "--timesteps", "4096", "--runs", str(root / "runs")
        )
        runs = sorted((root / "runs" / "tracelines").glob("*-airl-*"))
    return runs[-1]


def make_cohort(root: Path) -> Path:
    """100 synthetic TraceLines trajectories, 5 levels x 20 (made once)."""
    out = root / "cohort"
    if len(list(out.glob("*.npz"))) != 100:
        fastrl("cohort", "specs/tracelines.yaml", "--levels", "5", "--per-level", "20", "-o", str(out), "--no-progress")
    return out


def timed(cmd: list[str]) -> tuple[float, float]:
    """(wall, CPU) seconds of a subprocess, from launch to exit; CPU counts every process it waited for."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{res.stdout}\n{res.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", type=Path, help="a run directory (default: make a small AIRL run)")
    ap.add_argument("--trajectories", type=Path, help="a folder of .npz (default: make a 5 x 20 cohort)")
    ap.add_argument("--repeats", type=int, default=5, help="warm runs timed (median reported)")
    ap.add_argument("--out", type=Path, default=ROOT / "out", help="where the score outputs go")
    args = ap.parse_args()
    run = args.run or make_run(ROOT)
    trajectories = args.trajectories or make_cohort(ROOT)
    n = len(list(trajectories.glob("*.npz")))
    out = args.out / "scores.json"
    cmd = [sys.executable, "-m", "fastrl.cli", "score", str(trajectories), "--run", str(run), "-o", str(out)]
    cmd.append("--no-progress")
    print(f"machine: {machine()}")
    print(f"run: {run}\ntrajectories: {trajectories} ({n} files)\ncommand: {' '.join(cmd[1:])}")
    startup = statistics.median(timed([sys.executable, "-c", "import fastrl.runner.assessment"])[0] for _ in range(3))
    cold, cold_cpu = timed(cmd)
    print(f"first run (fills the run's caches if empty): {cold:.2f} s wall, {cold_cpu:.2f} s CPU")
    walls, cpus, breakdowns = [], [], []
    for _ in range(args.repeats):
        wall, cpu = timed(cmd)
        walls.append(wall)
        cpus.append(cpu)
        breakdowns.append(json.loads(out.read_text())["seconds"])
    median = statistics.median(walls)
    seconds = breakdowns[walls.index(sorted(walls)[len(walls) // 2])]
    print(
        f"fastrl score, {n} trajectories, whole command: median {median:.2f} s wall (best {min(walls):.2f}, "
        f"worst {max(walls):.2f}, {args.repeats} runs), CPU {statistics.median(cpus):.2f} s"
    )
    print("breakdown of the median run (s):")
    print(f"  python + imports             {startup:6.2f}   (python -c 'import fastrl.runner.assessment', median of 3)")
    for key in ("load", "references", "scoring", "report", "pictures"):
        if key in seconds:
            print(f"  {key:28s} {seconds[key]:6.2f}")
    rest = median - startup - sum(seconds.values())
    print(f"  {'rest (CLI, JSON, exit)':28s} {rest:6.2f}")
    print(f"load average after: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
