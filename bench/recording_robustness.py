"""Do the scores survive another recorder? A cohort written as other trackers would write it, scored by one run.

    python bench/recording_robustness.py                                # TraceLines classic, its newest assess run
    python bench/recording_robustness.py --task imagecentring --run RUN/learned

The family's 5 x 10 cohort of bench/validity.py (no actions) is written again as a tracker other than the
simulator's could have recorded it: resampled to 50 Hz and 10 Hz, at 60 Hz with +-4 ms of jitter on the time stamps,
with the clock started at 1234.5 s, and with white measurement noise on every coordinate (0.1 deg and 0.2 mm, 0.3
deg and 0.5 mm: an electromagnetic tracker's order). Each copy is scored by the same learned run (`fastrl score
--run`, no learning) and every score's Kendall tau-b against the skill labels printed beside the originals'. Then
how closely the top level's recordings hold each avatar: the cue's centring margin (tolerance minus angle) on the
samples where the cue is green, replayed in the task. Writes --json.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import math
import shutil
import time
from pathlib import Path

import numpy as np
from common import machine_line
from validity import ROOT, cohort
from video_validity import score, taus

NOISE = {"noise 0.1 deg 0.2 mm": (0.1, 0.2), "noise 0.3 deg 0.5 mm": (0.3, 0.5)}


def resampled(t: np.ndarray, p: np.ndarray, hz: float, jitter: float, rng) -> tuple[np.ndarray, np.ndarray]:
    """The coordinates interpolated onto a grid of `hz` (angles unwrapped), its stamps moved by up to +-jitter s."""
    from fastrl.data.frames import control_grid
    from fastrl.data.poses import resample_columns

    grid = control_grid(t, hz)
    if jitter:
        grid = np.sort(np.clip(grid + rng.uniform(-jitter, jitter, len(grid)), t[0], t[-1]))
        grid[0] = t[0]
    q = p.copy()
    q[:, 3:] = np.unwrap(q[:, 3:], axis=0)
    return grid, resample_columns(grid, t, q)


def noisy(p: np.ndarray, deg: float, mm: float, rng) -> np.ndarray:
    """White measurement noise: `deg` on the four angles, `mm` on the insertion (standard deviations)."""
    scale = np.array([math.radians(deg)] * 2 + [mm / 1000] + [math.radians(deg)] * 2)
    return p + rng.normal(0.0, 1.0, p.shape) * scale


def copies(folder: Path, out: Path, seed: int = 0) -> dict[str, Path]:
    """The cohort written as each recorder would, under out/NAME."""
    from fastrl.data.trajectory import Trajectory

    how = {
        "50 Hz": lambda t, p, rng: resampled(t, p, 50.0, 0.0, rng),
        "60 Hz, +-4 ms jitter": lambda t, p, rng: resampled(t, p, 60.0, 0.004, rng),
        "10 Hz": lambda t, p, rng: resampled(t, p, 10.0, 0.0, rng),
        "clock from 1234.5 s": lambda t, p, rng: (t + 1234.5, p),
        **{name: (lambda t, p, rng, d=d, m=m: (t, noisy(p, d, m, rng))) for name, (d, m) in NOISE.items()},
    }
    made = {}
    for k, (name, f) in enumerate(how.items()):
        rng = np.random.default_rng(seed + k)
        target = out / name.replace(" ", "_").replace(",", "").replace("+-", "pm")
        shutil.rmtree(target, ignore_errors=True)
        target.mkdir(parents=True)
        for file in sorted(folder.glob("*.npz")):
            traj = Trajectory.load(file)
            t, p = f(traj.time, traj.portal, rng)
            Trajectory(t, p, traj.meta).save(target / file.name)
        made[name] = target
    return made


def centring_margins(folder: Path, task: str, level: int) -> np.ndarray:
    """Degrees between the cue's centring tolerance and the angle, on every green sample of the level's replays."""
    from fastrl.data.trajectory import Trajectory
    from fastrl.env.fast_env import FastEnv
    from fastrl.spec import load_spec

    env = FastEnv(load_spec(Path(f"specs/{task}.yaml")))
    s, out = env.unwrapped.state, []
    for file in sorted(folder.glob(f"L{level}-*.npz")):
        traj = Trajectory.load(file)
        env.reset(seed=0, options={"portal": traj.portal[0]})
        for q in traj.portal[1:]:
            _, _, term, trunc, _ = env.replay_step(q)
            if s.green:
                out.append(math.degrees(s.tol_centring - s.centring))
            if term or trunc:
                break
    return np.array(out)


def newest_run(task: str, family: str, root: Path) -> Path:
    """The newest assessment's learned networks of the family (bench/validity.py's runs)."""
    runs = sorted((root / task / family / "runs" / task).glob("*-assess-*"))
    if not runs:
        raise SystemExit(f"no assessment of {task} {family} under {root}: run bench/validity.py first, or give --run")
    return runs[-1] / "learned"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", default="tracelines")
    parser.add_argument("--family", default="classic")
    parser.add_argument("--root", type=Path, default=ROOT)
    parser.add_argument("--run", type=Path, help="learned networks to score with (default: the newest assessment)")
    parser.add_argument("--json", type=Path, default=Path("docs/recording_robustness.json"))
    args = parser.parse_args()
    from fastrl.data.trajectory import Trajectory

    result = {"machine": machine_line(), "utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "rows": []}
    print(f"# {result['utc']} UTC, {result['machine']}", flush=True)
    folder = cohort(args.task, args.family, args.root)
    run = args.run or newest_run(args.task, args.family, args.root)
    result["run"] = str(run)
    labels = {f.stem: Trajectory.load(f).meta["skill"] for f in folder.glob("*.npz")}
    base = args.root / args.task / args.family / "recorders"
    for name, inputs in {"as recorded": folder, **copies(folder, base)}.items():
        report, secs = score(run, inputs, base / "scores" / name.replace(" ", "_") / "scores.json")
        tau = taus(report, labels)
        result["rows"].append({"input": name, "tau_b": tau, "seconds": secs})
        print(f"{name:<24} " + "  ".join(f"{k} {v:+.3f}" for k, v in tau.items()), flush=True)
    top = max(labels.values())
    margins = centring_margins(folder, args.task, top)
    pct = np.percentile(margins, [0, 10, 50]).round(2).tolist() if len(margins) else []
    result["centring_margin_deg"] = {"level": top, "green_samples": len(margins), "min_p10_median": pct}
    print(f"level {top}: centring margin on its {len(margins)} green samples, min / p10 / median {pct} deg")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=1))
    print(f"# ended {time.strftime('%H:%M', time.gmtime())} UTC, {machine_line()}")


if __name__ == "__main__":
    main()
