"""Scores from the endoscope video alone: the paper's protocol on a cohort's mp4s, beside the same cohort's kinematics.

    python bench/video_validity.py                                   # TraceLines, classic family, seed 0
    python bench/video_validity.py --task periscoping --skip-reencode
    python bench/video_validity.py --families mixed
    python bench/video_validity.py --by motion --skip-reencode         # learn from the best 10 by the motion too

For each family: the 5 x 10 cohort of bench/validity.py (no actions) is rendered to H.264 mp4 at the task's endoscope
size and control rate (`fastrl render-video`), then `fastrl assess VIDEOS --top 10 --by time` (`--by`: another rule)
learns from the best 10 videos (their portal coordinates read off the frames by the task's pose estimator, trained
once and cached) and scores all 50; the same protocol on the cohort's .npz files (the true portal coordinates) runs
beside it. Printed: Kendall tau-b against the skill labels of the learned reward and value, the heuristic, the
stopwatch, the path length and the subtasks, from video and from kinematics. Then the videos re-encoded at 25, 30 and
60 fps, at 96 and 192 px and at crf 35 are scored with the video run's networks (`fastrl score --run`), each tau-b
beside the originals'; and 100 videos of 10 s at 30 fps are scored, timed. Writes --json.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

from common import machine_line
from validity import SCORES, cohort

ROOT = Path("runs/bench-video")
REENCODES = {
    "25fps": {"fps": 25},
    "30fps": {"fps": 30},
    "60fps": {"fps": 60},
    "96px": {"size": 96},
    "192px": {"size": 192},
    "crf35": {"crf": 35},
}


def videos(folder: Path, out: Path) -> Path:
    """The cohort's endoscope videos, rendered once."""
    from fastrl.runner.score.video import render_videos

    files = sorted(folder.glob("*.npz"))
    if len(list(out.glob("*.mp4"))) != len(files):
        batch = render_videos(files, out, progress=False)
        assert not batch.errors, batch.errors
    return out


def reencode(
    src: Path,
    out: Path,
    *,
    fps: float | None = None,
    size: int | None = None,
    crf: int = 23,
    seconds: float | None = None,
    copies: int = 1,
) -> Path:
    """Each video decoded and written again (another rate, size, quality or length), `copies` times, once."""
    from fastrl.data.render_video import at_rate
    from fastrl.data.video import read_video, write_video

    files = sorted(src.glob("*.mp4"))
    if len(list(out.glob("*.mp4"))) == len(files) * copies:
        return out
    for f in files:
        v = read_video(f)
        frames, rate = (v.frames, v.fps) if fps is None else (at_rate(v.time, v.frames, fps), fps)
        if seconds is not None:
            frames = frames[: int(round(seconds * rate))]
        for k in range(copies):
            name = f.stem if copies == 1 else f"{f.stem}-{k}"
            write_video(out / f"{name}.mp4", frames, rate, crf=crf, size=None if size is None else (size, size))
    return out


def taus(report: dict, labels: dict[str, int]) -> dict:
    """Kendall tau-b against the labels of each score, the labels joined by subject (the file's stem); a report of
    several seeds ranks each learned score by its mean over them (the report's own figure)."""
    from fastrl.assess.ranking import rank_correlations
    from fastrl.assess.report import HIGHER_IS_BETTER, NORMALISED

    subject = {r["file"]: "-".join(r["file"].split("-")[:2]) for r in report["trajectories"]}  # L1-S01(-k)
    rows = [r for r in report["trajectories"] if subject[r["file"]] in labels]
    labelled = [labels[subject[r["file"]]] for r in rows]
    out = {}
    for k in SCORES:
        raw = k + "_raw" if k in NORMALISED else k
        if not rows or rows[0].get(raw) is None:
            continue
        sign = 1.0 if HIGHER_IS_BETTER[k] else -1.0
        out[k] = rank_correlations([sign * r[raw] for r in rows], labelled)["kendall_tau_b"]
    for k in report.get("seeds", {}).get("agreement", {}):  # the mean of each seed's standardised score
        out[k] = rank_correlations([r[k + "_z"] for r in rows], labelled)["kendall_tau_b"]
    return out


def protocol(inputs: Path, task: str, seed: int, root: Path, seeds: int = 1, by: str = "time"):
    """`fastrl assess INPUTS --top 10 --by BY [--seeds N]`, quiet; (what it did, seconds)."""
    from rich.console import Console

    from fastrl.runner.protocol import run_protocol

    t0 = time.perf_counter()
    done = run_protocol(
        [inputs],
        Path(f"specs/{task}.yaml"),
        top=10,
        by=by,
        overrides=[f"train.seed={seed}"],
        root=root,
        console=Console(stderr=True, quiet=True),
        progress=False,
        pictures=False,
        seeds=seeds,
    )
    return done, time.perf_counter() - t0


def score(run: Path, inputs: Path, output: Path):
    """`fastrl score --run RUN INPUTS`, quiet, no pictures; (report, seconds)."""
    from rich.console import Console

    from fastrl.runner.score.assessment import assess

    t0 = time.perf_counter()
    done = assess(
        [inputs],
        run=run,
        output=output,
        console=Console(stderr=True, quiet=True),
        progress=False,
        pictures=False,
        fresh=True,
    )
    return done.report, time.perf_counter() - t0


def line(name: str, t: dict) -> str:
    """One printed row of tau-b."""
    return f"{name:<28} " + "  ".join(f"{k} {t[k]:+.2f}" for k in SCORES if t.get(k) is not None)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--task", default="tracelines")
    parser.add_argument("--families", nargs="+", default=["classic"])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--seeds", type=int, default=1, help="learn on this many seeds and rank by their mean")
    parser.add_argument("--by", default="time", help="whom the protocol learns from (fastrl assess --by)")
    parser.add_argument("--root", type=Path, default=ROOT)
    parser.add_argument("--skip-kinematic", action="store_true")
    parser.add_argument("--skip-reencode", action="store_true")
    parser.add_argument("--json", type=Path, default=Path("docs/video_validity.json"))
    args = parser.parse_args()
    from fastrl.data.trajectory import Trajectory

    result = {"machine": machine_line(), "utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "rows": []}
    print(f"# {result['utc']} UTC, {result['machine']}", flush=True)

    def keep(row: dict) -> None:
        result["rows"].append(row)
        print(line(f"{row['family']} {row['input']}", row["tau_b"]) + f"  ({row['seconds']:.0f} s)", flush=True)
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=1))

    for family in args.families:
        base = args.root / args.task / family
        folder = cohort(args.task, family, args.root)
        labels = {f.stem: Trajectory.load(f).meta["skill"] for f in folder.glob("*.npz")}
        mp4 = videos(folder, base / "videos")
        learned_from, done = {"video": mp4, **({} if args.skip_kinematic else {"kinematic": folder})}, {}
        for name, inputs in learned_from.items():
            done[name], secs = protocol(inputs, args.task, args.seed, base / "runs" / args.by, args.seeds, args.by)
            taus_b = taus(done[name].assessment.report, labels)
            row = {
                "family": family,
                "input": name,
                "by": args.by,
                "seeds": args.seeds,
                "tau_b": taus_b,
                "seconds": secs,
            }
            keep({**row, "run": str(done[name].run)})
        if args.skip_reencode:
            continue
        learned = done["video"].learned[0]
        report, secs = score(learned, mp4, base / "scores" / "original" / "scores.json")
        keep({"family": family, "input": "video, scored again", "tau_b": taus(report, labels), "seconds": secs})
        for name, how in REENCODES.items():
            report, secs = score(learned, reencode(mp4, base / name, **how), base / "scores" / name / "scores.json")
            keep({"family": family, "input": f"video {name}", "tau_b": taus(report, labels), "seconds": secs})
        hundred = reencode(mp4, base / "100x10s", fps=30, seconds=10, copies=2)
        report, secs = score(learned, hundred, base / "scores" / "100x10s" / "scores.json")
        keep({"family": family, "input": "100 videos of 10 s (timed)", "tau_b": taus(report, labels), "seconds": secs})
    print(f"# ended {time.strftime('%H:%M', time.gmtime())} UTC, {machine_line()}")


if __name__ == "__main__":
    main()
