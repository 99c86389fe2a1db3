"""How long does `fastrl assess` take, and do its learned scores rank as well? This tree beside a reference tree.

    python bench/assess_speed.py --ref /work/ref-b712-assess                   # TraceLines classic, 3 pairs
    python bench/assess_speed.py --ref /work/ref-b712-assess --tasks periscoping imagecentring --repeats 1
    python bench/assess_speed.py --ref /work/ref-b712-assess --families depth mixed --seeds 1
    python bench/assess_speed.py --ref /work/ref-1a8e-assess --ensemble 3      # `fastrl assess --seeds 3`
    python bench/assess_speed.py --ref /work/ref-1a8e-assess --ensemble 3 --families ringing \
        --cohort runs/bench-outside/tracelines/ringing/cohort

The whole command as a user runs it, `fastrl assess COHORT --spec specs/TASK.yaml --top 10` (pictures included,
`--set train.seed=S` for each --seeds; with --ensemble N also `--seeds N`, N scorers from seed S on), in a fresh
process with PYTHONPATH at this tree and at --ref (a git worktree of the reference commit: `git worktree add
/work/ref-b712-assess b712f6b`), the two interleaved, each pair's order alternating. The cohort is
bench/validity.py's (5 levels x 10 subjects without actions, seed 0), or --cohort's. Printed per run: the wall time,
each scorer's generator steps, Kendall tau-b of the learned reward and value against the skill labels (the scorers'
mean, with several), with the machine and its load; then the median per tree. Writes --json
(docs/assess_speed.json).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import machine_line
from validity import ROOT, cohort

HERE = Path(__file__).resolve().parents[1]


def run_once(tree: Path, task: str, folder: Path, seed: int, sets: list[str], ensemble: int = 1) -> dict:
    """One `fastrl assess` (`--seeds ensemble`) in a fresh process importing fastrl from `tree`: wall time, each
    scorer's steps and the tau-b of the scores (the scorers' mean, with several)."""
    with tempfile.TemporaryDirectory(prefix="assess-speed-") as runs:
        command = [sys.executable, "-m", "fastrl.cli", "assess", str(folder.resolve()), "--spec"]
        command += [str(tree / "fastrl" / "specs" / f"{task}.yaml"), "--top", "10", "--runs", runs, "--no-progress"]
        command += [arg for s in [f"train.seed={seed}", *sets] for arg in ("--set", s)]
        command += ["--seeds", str(ensemble)] if ensemble > 1 else []
        env = {**os.environ, "PYTHONPATH": str(tree)}
        t0 = time.perf_counter()
        done = subprocess.run(command, env=env, cwd=runs, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if done.returncode:
            raise RuntimeError(f"{' '.join(command)} failed:\n{done.stderr[-2000:]}")
        (report,) = Path(runs).glob("*/*/scores.json")
        metas = sorted(Path(runs).glob("*/*/learned*/meta.json"))
        ranking = json.loads(report.read_text())["ranking"]
        steps = [json.loads(meta.read_text()).get("trained_timesteps") for meta in metas]
    taus = {k: ranking[k]["kendall_tau_b"] for k in ("reward", "value", "time")}
    return {"wall": wall, "steps": steps, "tau_b": taus, "load": os.getloadavg()[0]}


def kilo(steps) -> str:
    """Each scorer's steps in thousands (an int: one scorer, as the rows before --ensemble)."""
    return " + ".join(f"{n / 1000:.0f}k" for n in (steps if isinstance(steps, list) else [steps]))


def line(tree: str, task: str, family: str, seed: int, r: dict) -> str:
    """One run as a line."""
    t = r["tau_b"]
    return (
        f"{task} {family} s{seed} {tree}: {r['wall']:.1f} s, {kilo(r['steps'])} steps, "
        f"tau-b reward {t['reward']:.3f} value {t['value']:.3f} (time {t['time']:.3f}), load {r['load']:.2f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ref", type=Path, required=True, help="the reference tree (a worktree of its commit)")
    parser.add_argument("--tasks", nargs="+", default=["tracelines"])
    parser.add_argument("--families", nargs="+", default=["classic"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--ensemble", type=int, default=1, help="scorers per command (`fastrl assess --seeds N`)")
    parser.add_argument("--cohort", type=Path, help="this cohort folder instead of each family's (one --families name)")
    parser.add_argument("--repeats", type=int, default=3, help="pairs (this, reference) per task, family and seed")
    parser.add_argument("--set", dest="sets", action="append", default=[], help="spec change for this tree only")
    parser.add_argument("--json", type=Path, default=Path("docs/assess_speed.json"))
    args = parser.parse_args()
    trees = {"this": HERE, "ref": args.ref.resolve()}
    started = {"machine": machine_line(), "utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "sets": args.sets}
    print(f"# {started['utc']} UTC, {started['machine']}", flush=True)
    rows = []
    for task in args.tasks:
        for family in args.families:
            folder = args.cohort or cohort(task, family, ROOT)
            for seed in args.seeds:
                for k in range(args.repeats):
                    for name in ("this", "ref") if k % 2 == 0 else ("ref", "this"):
                        sets = args.sets if name == "this" else []
                        r = run_once(trees[name], task, folder, seed, sets, args.ensemble)
                        row = {"tree": name, "task": task, "family": family, "seed": seed, "ensemble": args.ensemble}
                        rows.append({**row, **({"cohort": str(args.cohort)} if args.cohort else {}), **r})
                        print(line(name, task, family, seed, r), flush=True)
                args.json.parent.mkdir(parents=True, exist_ok=True)
                args.json.write_text(json.dumps({**started, "ref": str(args.ref), "rows": rows}, indent=1))
    print(f"# ended {time.strftime('%H:%M', time.gmtime())} UTC, {machine_line()}")
    print("| task | family | seed | tree | median wall | runs | steps | tau-b reward | tau-b value |")
    print("|---|---|---|---|---|---|---|---|---|")
    for task in args.tasks:
        for family in args.families:
            for seed in args.seeds:
                for name in ("this", "ref"):
                    mine = [
                        r for r in rows if (r["task"], r["family"], r["seed"], r["tree"]) == (task, family, seed, name)
                    ]
                    walls = ", ".join(f"{r['wall']:.0f}" for r in mine)
                    last = mine[-1]
                    print(
                        f"| {task} | {family} | {seed} | {name} | {statistics.median(r['wall'] for r in mine):.0f} s "
                        f"| {walls} | {kilo(last['steps'])} | {last['tau_b']['reward']:.2f} "
                        f"| {last['tau_b']['value']:.2f} |"
                    )


if __name__ == "__main__":
    main()
