"""`fastrl score --run RUN` on archives of 1,000 and 5,000 trajectories: wall time, peak memory, and a resume.

    python bench/score_scale.py --run RUN_DIR --cohort DIR              # DIR: a cohort of TraceLines .npz
    python bench/score_scale.py --run RUN_DIR --cohort DIR --counts 1000,5000 --interrupt-at 400

Each archive is the cohort's files linked (or copied) under new names until it holds N files: the scores repeat,
the cost of scoring and the memory do not depend on that. Without --run, a small AIRL run is made as in
bench/score_speed.py; without --cohort, a 5 x 20 cohort. For each N, `python -m fastrl.cli score ARCHIVE --run RUN
--fresh` runs as a subprocess; the resident memory (RSS) of it and of every process it starts (the forked helper)
is sampled every 0.1 s: the peak of each process and of their sum are printed with the wall time. Then the
largest-but-one archive is scored with SIGINT sent once the journal holds --interrupt-at files, and scored again:
the rerun's wall time, how many files it read from the journal and whether its report equals the uninterrupted one.
Prints the machine (CPU model, cores) and the load averages before and after. --resume-only: that last case alone.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
from common import load_after, load_average, machine_line
from score_speed import fastrl, make_cohort, make_run

ROOT = Path("runs/bench-scale")


def archive(cohort: Path, n: int, root: Path) -> Path:
    """A folder of n files: the cohort's, linked under new names (copied where links fail)."""
    out = root / f"archive-{n}"
    sources = sorted(cohort.glob("*.npz"))
    if len(list(out.glob("*.npz"))) == n:
        return out
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    for k in range(n):
        src = sources[k % len(sources)]
        dst = out / f"{src.stem}_copy{k // len(sources):03d}.npz"
        try:
            os.link(src, dst)
        except OSError:
            shutil.copy2(src, dst)
    return out


def watched(cmd: list[str], stop_when=None) -> dict:
    """Run cmd, sampling the RSS of it and its descendants; `stop_when()` True sends it SIGINT once."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_sigint_default)
    peaks: dict[int, int] = {}
    total, interrupted = 0, False
    root = psutil.Process(proc.pid)
    while proc.poll() is None:
        try:
            procs = [root, *root.children(recursive=True)]
            rss = {p.pid: p.memory_info().rss for p in procs}
        except psutil.Error:
            rss = {}
        for pid, r in rss.items():
            peaks[pid] = max(peaks.get(pid, 0), r)
        total = max(total, sum(rss.values()))
        if stop_when is not None and not interrupted and stop_when():
            proc.send_signal(signal.SIGINT)
            interrupted = True
        time.sleep(0.1)
    stdout, stderr = proc.communicate()
    return {
        "wall": time.perf_counter() - t0,
        "code": proc.returncode,
        "main_peak": peaks.get(proc.pid, 0),
        "other_peaks": sorted((v for k, v in peaks.items() if k != proc.pid), reverse=True),
        "sum_peak": total,
        "stdout": stdout,
        "stderr": stderr,
    }


def _sigint_default() -> None:
    """In the child: SIGINT as Python expects it (a job started with & in a script inherits it ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def mb(n: int) -> str:
    """Bytes as MB."""
    return f"{n / 1e6:.0f} MB"


def lines(path: Path) -> int:
    """Lines in a file (0 if missing)."""
    try:
        return path.read_bytes().count(b"\n")
    except OSError:
        return 0


def rows(report: Path) -> list:
    """A report's per-trajectory rows."""
    return json.loads(report.read_text())["trajectories"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", type=Path, help="a run directory (default: make a small AIRL run)")
    ap.add_argument("--cohort", type=Path, help="a folder of .npz to copy from (default: make a 5 x 20 cohort)")
    ap.add_argument("--counts", default="1000,5000", help="archive sizes, comma-separated")
    ap.add_argument("--interrupt-at", type=int, default=400, help="journaled files at which SIGINT is sent")
    ap.add_argument("--root", type=Path, default=ROOT, help="where archives and outputs go")
    ap.add_argument("--resume-only", action="store_true", help="only the interrupted case (after a full run)")
    args = ap.parse_args()
    run = args.run or make_run(args.root)
    cohort = args.cohort or make_cohort(args.root)
    counts = [int(c) for c in args.counts.split(",")]
    print(f"machine: {machine_line()}")
    print(f"run: {run}\ncohort copied from: {cohort} ({len(list(cohort.glob('*.npz')))} files)")
    print(fastrl("--version").stdout.strip())
    results = {}
    for n in [] if args.resume_only else counts:
        folder = archive(cohort, n, args.root)
        out = args.root / f"out-{n}" / "scores.json"
        cmd = [sys.executable, "-m", "fastrl.cli", "score", str(folder), "--run", str(run), "-o", str(out)]
        r = watched([*cmd, "--no-progress", "--fresh"])
        if r["code"] != 0:
            sys.exit(f"{' '.join(cmd)} failed ({r['code']}):\n{r['stderr'][-3000:]}")
        seconds = json.loads(out.read_text())["seconds"]
        results[n] = r
        helper = f", helper {mb(r['other_peaks'][0])}" if r["other_peaks"] else ""
        print(
            f"{n} files: {r['wall']:.1f} s wall (scoring {seconds['scoring']:.1f} s, pictures "
            f"{seconds.get('pictures', 0):.1f} s); peak RSS main {mb(r['main_peak'])}{helper}, "
            f"both at once {mb(r['sum_peak'])}; load now {load_average()}"
        )
    if len(results) > 1:
        lo, hi = results[counts[0]], results[counts[-1]]
        print(
            f"peak RSS {counts[-1]} vs {counts[0]} files: main {hi['main_peak'] / lo['main_peak']:.2f}x, "
            f"both processes {hi['sum_peak'] / lo['sum_peak']:.2f}x"
        )
    n = counts[-2] if len(counts) > 1 else counts[0]
    folder, out = archive(cohort, n, args.root), args.root / "out-interrupted" / "scores.json"
    journal = out.parent / "scores.journal.jsonl"
    cmd = [sys.executable, "-m", "fastrl.cli", "score", str(folder), "--run", str(run), "-o", str(out), "--no-progress"]
    journal.unlink(missing_ok=True)  # a journal from an earlier bench would look like progress at once
    first = watched([*cmd, "--fresh"], stop_when=lambda: lines(journal) > args.interrupt_at)
    kept = lines(journal) - 1
    print(
        f"interrupted ({n} files): SIGINT after {first['wall']:.1f} s, exit {first['code']}, {kept} files in the "
        f"journal; its last words: {first['stderr'].strip().splitlines()[-1:]}"
    )
    second = watched(cmd)
    said = [line for line in second["stdout"].splitlines() if line.startswith("scored ")]
    whole = args.root / f"out-{n}" / "scores.json"
    same = rows(out) == rows(whole) if whole.exists() else None
    print(
        f"rerun: {second['wall']:.1f} s wall, exit {second['code']}, peak RSS main {mb(second['main_peak'])}; "
        f"{said[-1] if said else second['stderr'][-500:]}; rows equal to the uninterrupted run's: {same}"
    )
    print(load_after())


if __name__ == "__main__":
    main()
