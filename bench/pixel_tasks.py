"""Periscoping and ImageCentring from pixels: each task's spec with tracelines_pixels.yaml's pixel settings.

    python bench/pixel_tasks.py --tasks periscoping imagecentring --seeds 0 [--runs DIR] [--json OUT]

The pixel settings are read from specs/tracelines_pixels.yaml, the one place they are decided: its endoscope image
(`observation.image`), its PPO, encoder and warm start (`train`, all but the algorithm and the seed) and its sampled
evaluation. Everything else (the task, its reward, its evaluation seeds and stop at 95%) is the task's own spec.
Each run is the whole `fastrl run` command; printed per run: the share of subtasks its final evaluation
completed, the success rate, the PPO steps and the wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import yaml
from common import ROOT, machine_line, utc_stamp

PIXEL_SPEC = ROOT / "specs" / "tracelines_pixels.yaml"
TAKEN = {"observation": ("image",), "train": None, "evaluate": ("sampled",)}  # None: the whole section
KEPT = ("algo", "seed")  # the task's own


def dotted(prefix: str, value) -> list[str]:
    """`--set` overrides (dotted.path=value, value as YAML flow) for every leaf of a mapping."""
    if isinstance(value, dict):
        return [o for k, v in value.items() for o in dotted(f"{prefix}.{k}", v)]
    return [f"{prefix}={yaml.safe_dump(value, default_flow_style=True).strip().removesuffix('...').strip()}"]


def pixel_overrides() -> list[str]:
    """The pixel spec's image, training and evaluation settings as overrides of another task's spec."""
    pixel = yaml.safe_load(PIXEL_SPEC.read_text())
    out = []
    for section, keys in TAKEN.items():
        for key, value in pixel[section].items():
            if (keys is None and key not in KEPT) or (keys is not None and key in keys):
                out += dotted(f"{section}.{key}", value)
    return out


def one_run(task: str, seed: int, runs: Path) -> dict:
    """`fastrl run` of the task from pixels; its final evaluation, steps and wall time."""
    before = set(runs.glob(f"{task}/*"))
    command = [sys.executable, "-m", "fastrl.cli", "run", str(ROOT / "specs" / f"{task}.yaml"), "--seed", str(seed)]
    command += ["--runs", str(runs), "--no-progress"] + [a for o in pixel_overrides() for a in ("--set", o)]
    t0 = time.perf_counter()
    done = subprocess.run(command, check=False, env={**os.environ, "MUJOCO_GL": "egl"})
    wall = time.perf_counter() - t0
    new = sorted(set(runs.glob(f"{task}/*")) - before)
    if done.returncode != 0 or not new or not (new[-1] / "eval.json").exists():
        return {"task": task, "seed": seed, "failed": done.returncode, "wall_s": wall}
    run = new[-1]
    agent = json.loads((run / "eval.json").read_text())["agent"]
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    periodic = [(r["timesteps"], r["eval/subtasks"]) for r in rows if "eval/subtasks" in r]
    return {
        "task": task,
        "seed": seed,
        "run": str(run),
        "subtasks": agent["subtasks_completed"],
        "success": agent["success_rate"],
        "episode_time": agent["episode_time_mean"],
        "ppo_steps": max((r.get("timesteps", 0) for r in rows), default=0),
        "periodic": periodic,
        "wall_s": wall,
    }


def main() -> None:
    """Run every task and seed from pixels and print one line each."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tasks", nargs="+", default=["periscoping", "imagecentring"])
    p.add_argument("--seeds", nargs="+", type=int, default=[0])
    p.add_argument("--runs", type=Path, default=ROOT / "runs" / "pixel-tasks")
    p.add_argument("--json", type=Path)
    args = p.parse_args()
    print(f"{utc_stamp()}  {machine_line()}", flush=True)
    print("overrides: " + " ".join(pixel_overrides()), flush=True)
    rows = []
    for task in args.tasks:
        for seed in args.seeds:
            rows.append(r := one_run(task, seed, args.runs))
            if "failed" in r:
                print(f"{task} seed {seed}: failed (exit {r['failed']}) after {r['wall_s']:.0f} s", flush=True)
                continue
            print(
                f"{task} seed {seed}: {r['subtasks']:.1%} of subtasks, success {r['success']:.0%}, "
                f"{r['episode_time']:.1f} s per episode; {r['ppo_steps']:,} PPO steps, "
                f"wall {r['wall_s'] / 60:.1f} min; periodic {r['periodic']}",
                flush=True,
            )
    print(f"{utc_stamp()}  {machine_line()}", flush=True)
    if args.json:
        args.json.write_text(json.dumps({"machine": machine_line(), "utc": utc_stamp(), "runs": rows}, indent=1))


if __name__ == "__main__":
    main()
