"""Same spec and seed, two source trees: are the runs, cohorts and scores identical? (a refactor's check)

    python bench/same_seed_runs.py --reference /work/base --root /tmp/same-seed

For each bundled task spec, in this tree and in the reference tree (a git worktree of the commit before the
change): `fastrl run` on a short budget, `fastrl cohort` of 4 trainees, and `fastrl score --run` of that cohort.
Compared: the final weights, normalisation and exported networks byte for byte, eval.json, the cohort's arrays and
scores.json (wall times left out). Exit 1 on any difference.
"""

from __future__ import annotations

import argparse
import filecmp
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from common import ROOT, machine_line, utc_stamp

SPECS = ("tracelines", "imagecentring", "periscoping", "triangulation", "loose_bodies", "liver_tour")
TIMED = ("seconds", "wall", "elapsed", "per_second", "fps", "created", "date", "started", "finished", "path")


def fastrl(tree: Path, *args: str) -> None:
    """Run the fastrl CLI of a source tree (its own code first on the path)."""
    env = dict(os.environ, PYTHONPATH=str(tree), MUJOCO_GL="egl")
    subprocess.run([sys.executable, "-m", "fastrl.cli", *args], cwd=tree, env=env, check=True, capture_output=True)


def study_off(tree: Path, spec: str) -> list[str]:
    """The override that keeps `fastrl run` to one training where the spec runs the paper's study instead."""
    text = (tree / "fastrl" / "specs" / f"{spec}.yaml").read_text()
    key = next((k for k in ("study", "experiment") if f"\n{k}:" in text), None)
    return ["--set", f"{key}.enabled=false"] if key else []


def produce(tree: Path, spec: str, out: Path, timesteps: int) -> Path:
    """A short run, a small cohort and its scores; the run folder."""
    runs = out / "runs"
    fastrl(tree, "run", spec, "--timesteps", str(timesteps), "--seed", "0", "--runs", str(runs), "--no-progress",
           "--set", "evaluate.episodes=2", *study_off(tree, spec))  # fmt: skip
    run = next(p for p in runs.rglob("eval.json")).parent
    fastrl(tree, "cohort", spec, "--levels", "2", "--per-level", "2", "-o", str(out / "cohort"), "--no-progress")
    fastrl(tree, "score", str(out / "cohort"), "--run", str(run), "-o", str(out / "scores.json"),
           "--no-pictures", "--no-progress")  # fmt: skip
    return run


def untimed(node):
    """JSON data without the fields that hold wall times, dates or paths."""
    if isinstance(node, dict):
        return {k: untimed(v) for k, v in node.items() if not any(t in k for t in TIMED)}
    if isinstance(node, list):
        return [untimed(v) for v in node]
    return node


def differences(a: Path, run_a: Path, b: Path, run_b: Path) -> list[str]:
    """What differs between the two trees' products."""
    out = []
    files = ["final/weights.pt", "final/normalize.npz"] + [
        str(p.relative_to(run_a)) for p in sorted((run_a / "networks").glob("*.safetensors"))
    ]
    out += [f for f in files if not filecmp.cmp(run_a / f, run_b / f, shallow=False)]
    for x, y in ((run_a / "eval.json", run_b / "eval.json"), (a / "scores.json", b / "scores.json")):
        if untimed(json.loads(x.read_text())) != untimed(json.loads(y.read_text())):
            out.append(x.name)
    for npz in sorted((a / "cohort").glob("*.npz")):
        x, y = np.load(npz), np.load(b / "cohort" / npz.name)
        if any(k not in y.files or not np.array_equal(x[k], y[k]) for k in x.files if k != "meta"):
            out.append(f"cohort/{npz.name}")
    return out


def main() -> None:
    """Produce and compare every spec's run, cohort and scores in both trees."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--reference", type=Path, required=True, help="the other source tree (a git worktree)")
    p.add_argument("--root", type=Path, required=True, help="an empty folder for both trees' products")
    p.add_argument("--timesteps", type=int, default=4096)
    p.add_argument("--specs", nargs="+", default=list(SPECS))
    args = p.parse_args()
    print(f"{utc_stamp()}  {machine_line()}")
    failed = False
    for spec in args.specs:
        here, there = args.root / "here" / spec, args.root / "reference" / spec
        run_here = produce(ROOT, spec, here, args.timesteps)
        run_there = produce(args.reference.resolve(), spec, there, args.timesteps)
        diff = differences(here, run_here, there, run_there)
        failed |= bool(diff)
        print(f"{spec:14s} {'identical' if not diff else 'DIFFERENT: ' + ', '.join(diff)}", flush=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
