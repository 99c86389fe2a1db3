"""How long the whole `fastrl run SPEC` command takes on its default budget, recording included, beside a reference.

    python bench/run_speed.py                                            # specs/tracelines.yaml, 3 runs
    python bench/run_speed.py --repeats 5 --reference /work/ref-6dabe3e  # interleaved with another checkout

Each repeat runs `python -m fastrl.cli run SPEC` as a subprocess from the checkout (PYTHONPATH pointing at it)
into a temporary runs folder and times it from launch to exit. With --reference (a checkout of another commit, e.g.
`git worktree add /work/ref-6dabe3e 6dabe3e`), the same command from that checkout runs interleaved with this one,
one of each per repeat. This checkout runs twice per repeat: first with the scripted expert's evaluation
forgotten (its memo in the fastrl cache removed: a spec's first run on a machine), then remembered. Prints the
machine and its load, the median, best and worst wall times, the CPU time of the command (every process it waited
for), and the median run's phases from its meta.json: training (its steps) and the final evaluation (the agent's
episodes with the recording's images, and the scripted expert's), the rest being start-up, building the learner,
saving and exit. Issue 41 asks <= 12 s for TraceLines.
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
import tempfile
import time
from pathlib import Path

from common import load_after, machine_line

from fastrl.cache import cache_dir

HERE = Path(__file__).resolve().parent.parent  # this checkout: its fastrl is the one timed


class Side:
    """One checkout's `fastrl run`, its wall and CPU times and its runs' meta."""

    def __init__(self, name: str, root: Path, spec: Path, cold: bool = False):
        self.name, self.root, self.spec, self.cold = name, root.resolve(), spec.resolve(), cold
        self.walls: list[float] = []
        self.cpus: list[float] = []
        self.metas: list[dict] = []

    def time_once(self) -> None:
        """One timed run into a fresh runs folder."""
        with tempfile.TemporaryDirectory(prefix="run-speed-") as runs:
            cmd = [sys.executable, "-m", "fastrl.cli", "run", str(self.spec), "--runs", runs, "--no-progress"]
            env = os.environ | {"PYTHONPATH": str(self.root)}
            if self.cold:  # the scripted expert's evaluation not yet remembered: a spec's first run on a machine
                shutil.rmtree(cache_dir() / "expert", ignore_errors=True)
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            res = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=self.root)
            wall = time.perf_counter() - t0
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            if res.returncode != 0:
                sys.exit(f"{' '.join(cmd)} failed:\n{res.stdout}\n{res.stderr}")
            (meta,) = Path(runs).glob("*/*/meta.json")
            self.metas.append(json.loads(meta.read_text()))
        self.walls.append(wall)
        self.cpus.append((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime))

    def summary(self) -> str:
        """Median (best, worst) wall, median CPU, and the median run's phases."""
        k = self.walls.index(sorted(self.walls)[len(self.walls) // 2])
        meta = self.metas[k]
        train, evaluation = meta.get("train_seconds", float("nan")), meta.get("eval_seconds", float("nan"))
        return (
            f"median {self.walls[k]:.2f} s wall (best {min(self.walls):.2f}, worst {max(self.walls):.2f}, "
            f"{len(self.walls)} runs), CPU {statistics.median(self.cpus):.2f} s; its training {train:.2f} s "
            f"({meta.get('trained_timesteps')} steps), final evaluation {evaluation:.2f} s, the rest "
            f"{self.walls[k] - train - evaluation:.2f} s"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spec", type=Path, default=HERE / "specs" / "tracelines.yaml", help="the spec run")
    ap.add_argument("--repeats", type=int, default=3, help="runs timed per checkout (median reported)")
    ap.add_argument("--reference", type=Path, help="a checkout of the reference commit, timed interleaved")
    args = ap.parse_args()
    sides = [Side("this checkout, first run", HERE, args.spec, cold=True), Side("this checkout", HERE, args.spec)]
    if args.reference is not None:
        sides.insert(0, Side(f"reference {args.reference}", args.reference, args.spec))
    print(f"machine: {machine_line()}")
    print(f"command: fastrl run {args.spec} (whole command, launch to exit)")
    for _ in range(args.repeats):
        for side in sides:
            side.time_once()
            print(f"  {side.name}: {side.walls[-1]:.2f} s", flush=True)
    for side in sides:
        print(f"fastrl run, {side.name}: {side.summary()}")
    if args.reference is not None:
        for side in sides[1:]:
            ratio = statistics.median(side.walls) / statistics.median(sides[0].walls)
            print(f"{side.name} / reference, median wall: {ratio:.2f}")
    print(load_after())


if __name__ == "__main__":
    main()
