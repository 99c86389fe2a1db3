"""How long the whole `fastrl score` command takes on 100 trajectories, start-up, figures and recording included.

    python bench/score_speed.py                                  # makes an AIRL run and a 5 x 20 TraceLines cohort
    python bench/score_speed.py --run RUN_DIR --trajectories DIR --repeats 7
    python bench/score_speed.py --run RUN_DIR --trajectories DIR --reference /work/ref-b712   # beside a reference

Without --run, a small AIRL run of TraceLines (`fastrl irl ... --timesteps 4096`; the cost of scoring does not
depend on how well it learned) is made under runs/bench-score; without --trajectories, a synthetic cohort
(`fastrl cohort --levels 5 --per-level 20`). Each repeat runs `python -m fastrl.cli score DIR --run RUN` as a
subprocess and times it from launch to exit; the first run fills the run's caches (reference scores, the scripted
expert's paths per seed) and is reported apart as the cold run. With --reference (a checkout of another commit, e.g.
`git worktree add /work/ref-b712 b712f6b`), the same command from that checkout (PYTHONPATH pointing at it) runs
interleaved with this one, each repeat one of each, into its own output folder. Prints the machine and its load, the
median, best and worst warm wall times, the CPU time of the command (both processes), and the breakdown: Python with
fastrl's imports, loading the run, scoring (replay and networks), the report, and figures + recording (from
scores.json's seconds).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from common import load_after, machine_line

HERE = Path(__file__).resolve().parent.parent  # this checkout: its fastrl is the one timed
ROOT = Path("runs/bench-score")


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


def timed(cmd: list[str], root: Path = HERE) -> tuple[float, float]:
    """(wall, CPU) seconds of a subprocess running fastrl from `root`, from launch to exit; CPU counts every process
    it waited for."""
    env = os.environ | {"PYTHONPATH": str(root)}  # and run from there: `python -m` puts the working folder first
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=root)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{res.stdout}\n{res.stderr}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


class Side:
    """One checkout's command, its timings and its report's seconds."""

    def __init__(self, name: str, root: Path, trajectories: Path, run: Path, out: Path):
        self.name, self.root, self.out = name, root, out.resolve() / "scores.json"
        self.cmd = [
            sys.executable,
            "-m",
            "fastrl.cli",
            "score",
            str(trajectories.resolve()),
            "--run",
            str(run.resolve()),
        ]
        self.cmd += ["-o", str(self.out), "--no-progress"]
        self.walls: list[float] = []
        self.cpus: list[float] = []
        self.seconds: list[dict] = []

    def time_once(self) -> None:
        """One timed run of the command."""
        wall, cpu = timed(self.cmd, self.root)
        self.walls.append(wall)
        self.cpus.append(cpu)
        self.seconds.append(json.loads(self.out.read_text())["seconds"])

    def summary(self) -> str:
        """Median (best, worst) wall and median CPU."""
        return (
            f"median {statistics.median(self.walls):.2f} s wall (best {min(self.walls):.2f}, worst "
            f"{max(self.walls):.2f}, {len(self.walls)} runs), CPU {statistics.median(self.cpus):.2f} s"
        )

    def breakdown(self, startup: float) -> list[str]:
        """The report's seconds of the median run, and the rest."""
        median = statistics.median(self.walls)
        seconds = self.seconds[self.walls.index(sorted(self.walls)[len(self.walls) // 2])]
        lines = [f"  python + imports             {startup:6.2f}   (python -c 'import fastrl.runner.score.assessment')"]
        lines += [
            f"  {k:28s} {seconds[k]:6.2f}"
            for k in ("load", "references", "scoring", "report", "pictures")
            if k in seconds
        ]
        lines.append(f"  {'rest (CLI, JSON, exit)':28s} {median - startup - sum(seconds.values()):6.2f}")
        return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", type=Path, help="a run directory (default: make a small AIRL run)")
    ap.add_argument("--trajectories", type=Path, help="a folder of .npz (default: make a 5 x 20 cohort)")
    ap.add_argument("--repeats", type=int, default=5, help="warm runs timed (median reported)")
    ap.add_argument("--out", type=Path, default=ROOT / "out", help="where the score outputs go")
    ap.add_argument("--reference", type=Path, help="a checkout of the reference commit, timed interleaved")
    args = ap.parse_args()
    run = args.run or make_run(ROOT)
    trajectories = args.trajectories or make_cohort(ROOT)
    n = len(list(trajectories.glob("*.npz")))
    sides = [Side("this checkout", HERE, trajectories, run, args.out)]
    if args.reference is not None:  # its own copy of the run: the run's caches are keyed by the version's spec hash
        ref_run = args.out / "reference-run"
        shutil.rmtree(ref_run, ignore_errors=True)
        shutil.copytree(run, ref_run)
        sides.insert(
            0,
            Side(
                f"reference {args.reference}", args.reference.resolve(), trajectories, ref_run, args.out / "reference"
            ),
        )
    print(f"machine: {machine_line()}")
    print(f"run: {run}\ntrajectories: {trajectories} ({n} files)\ncommand: {' '.join(sides[-1].cmd[1:])}")
    imports = [sys.executable, "-c", "import fastrl.runner.score.assessment"]
    for side in sides:
        where = [sys.executable, "-c", "import fastrl; print(fastrl.__file__)"]
        found = subprocess.run(
            where, capture_output=True, text=True, cwd=side.root, env=os.environ | {"PYTHONPATH": str(side.root)}
        )
        print(f"{side.name}: fastrl from {found.stdout.strip()}")
    startup = {s.name: statistics.median(timed(imports, s.root)[0] for _ in range(3)) for s in sides}
    for side in sides:
        cold, cold_cpu = timed(side.cmd, side.root)
        print(f"{side.name}: first run (fills the run's caches if empty): {cold:.2f} s wall, {cold_cpu:.2f} s CPU")
    for _ in range(args.repeats):
        for side in sides:
            side.time_once()
    for side in sides:
        print(f"fastrl score, {n} trajectories, whole command, {side.name}: {side.summary()}")
    if len(sides) == 2:
        ratio = statistics.median(sides[1].walls) / statistics.median(sides[0].walls)
        print(f"this checkout / reference, median wall: {ratio:.2f}")
    for side in sides:
        print(f"breakdown of the median run, {side.name} (s):")
        print("\n".join(side.breakdown(startup[side.name])))
    print(load_after())


if __name__ == "__main__":
    main()
