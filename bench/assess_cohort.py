"""Do the scores rank a synthetic cohort by skill? Table 1 per task, and the time to score 100 trajectories.

    python bench/assess_cohort.py                  # 3 tasks x 5 levels x 10 trainees, GAIL and AIRL runs
    python bench/assess_cohort.py --tasks tracelines --timing-only
    python bench/assess_cohort.py --irl-root runs/other-irl-runs --seed 1 --out /tmp/s1.json   # other runs
    python bench/assess_cohort.py --across docs/assess_cohort.json /tmp/s1.json   # level-means tau-b per seed

For each task: a cohort (`fastrl cohort SPEC --levels 5 --per-level 10`, written once under
runs/bench-assess/<task>/cohort) is scored with each inverse-RL run of bench/irl_tasks.py (the newest GAIL and
AIRL runs of the seed under runs/bench-irl/<task>: its learned reward r_psi and value V_phi) by the same code as
`fastrl score --run RUN cohort/`. Prints, per task, the Table 1-style mean ± sd per level of the normalised
scores (0 = random policy, 1 = scripted expert) and Kendall tau-b (with 95% bootstrap CI) of each score against
the true level. Timing: a TraceLines cohort of 5 x 20 = 100 trajectories scored (replay included) with the AIRL
run, best of 3, references cached, no pictures. Writes docs/assess_cohort.json.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

from common import machine_line

TASKS = ("imagecentring", "periscoping", "tracelines")
ROOT = Path("runs/bench-assess")


def cohort_dir(task: str, levels: int, per_level: int) -> Path:
    """The cohort's folder, generated on first use and again when the task's world (its task hash) has changed."""
    from fastrl.data.cohort import make_cohort
    from fastrl.data.trajectory import Trajectory
    from fastrl.spec import load_spec, task_hash

    spec = load_spec(f"specs/{task}.yaml")
    out = ROOT / task / f"cohort-{levels}x{per_level}"
    files = sorted(out.glob("*.npz"))
    if len(files) == levels * per_level and Trajectory.load(files[0]).meta.get("task_hash") == task_hash(spec):
        return out
    out.mkdir(parents=True, exist_ok=True)
    for traj in make_cohort(spec, levels, per_level, seed=0):
        traj.save(out / f"{traj.meta['subject']}.npz")
    return out


def irl_run(task: str, algorithm: str, root: Path, seed: int = 0) -> Path | None:
    """The newest inverse-RL run of bench/irl_tasks.py under root for a task, algorithm and training seed: a sweep's
    trial (ROOT/TASK/<time>-sweep/cN_algorithm=ALGO_sSEED) or an older run (ROOT/TASK/<time>-ALGO-ppo-sSEED)."""
    base = Path(root, task)
    found = [*base.glob(f"*-{algorithm}-ppo-s{seed}"), *base.glob(f"*-sweep/c*_algorithm={algorithm}_s{seed}")]
    found = [f for f in found if (f / "eval.json").exists()]
    return max(found, key=lambda f: f.relative_to(base).parts[0], default=None)  # the newest by its time stamp


def score_task(task: str, levels: int, per_level: int, root: Path, seed: int = 0) -> dict:
    """Both algorithms' reports on the task's cohort."""
    from fastrl.runner.score.assessment import assess

    cohort = cohort_dir(task, levels, per_level)
    out = {}
    for algorithm in ("airl", "gail"):
        run = irl_run(task, algorithm, root, seed)
        if run is None:
            print(f"{task}: no {algorithm} run under {root}/{task}: skipped")
            continue
        result = assess(
            [cohort], run=run, output=ROOT / root.name / task / f"{algorithm}-s{seed}" / "scores.json", progress=False
        )
        out[algorithm] = {"run": str(run), "report": result.report, "seconds": result.seconds}
    return out


def table(task: str, reports: dict) -> None:
    """Table 1-style markdown: mean ± sd per level, then tau-b per score."""
    airl, gail = reports.get("airl", {}).get("report"), reports.get("gail", {}).get("report")
    base = airl or gail
    cols = [
        ("heuristic", base, "heuristic"),
        ("r_psi (AIRL)", airl, "reward"),
        ("V_phi (AIRL)", airl, "value"),
        ("h (AIRL)", airl, "potential"),
        ("r (GAIL)", gail, "reward"),
        ("V (GAIL)", gail, "value"),
        ("path length (m)", base, "path_length"),
        ("time (s)", base, "time"),
    ]
    cols = [c for c in cols if c[1] is not None]
    print(f"\n### {task}\n")
    print("| level | " + " | ".join(c[0] for c in cols) + " |")
    print("|---|" + "---|" * len(cols))
    for g in base["groups"]:
        cells = []
        for _, rep, key in cols:
            grp = next(x for x in rep["groups"] if x["subject"] == g["subject"])
            cells.append("-" if grp[key] is None else f"{grp[key]:.3g} ± {grp[key + '_sd']:.2g}")
        print(f"| {g['subject']} | " + " | ".join(cells) + " |")
    cells = []
    for _, rep, key in cols:
        r = rep["ranking"].get(key)
        cells.append(
            "-"
            if not r or r["kendall_tau_b"] is None
            else f"{r['kendall_tau_b']:.2f} [{r['kendall_ci'][0]:.2f}, {r['kendall_ci'][1]:.2f}]"
        )
    print("| Kendall tau-b vs level | " + " | ".join(cells) + " |")
    print(
        "| Kendall tau-b of the level means | "
        + " | ".join(
            "-"
            if rep["ranking"].get(key, {}).get("kendall_tau_b_of_level_means") is None
            else f"{rep['ranking'][key]['kendall_tau_b_of_level_means']:.2f}"
            for _, rep, key in cols
        )
        + " |"
    )


SCORED = (
    ("heuristic", "airl", "heuristic"),
    ("r_psi (AIRL)", "airl", "reward"),
    ("V_phi (AIRL)", "airl", "value"),
    ("h (AIRL)", "airl", "potential"),
    ("r (GAIL)", "gail", "reward"),
    ("V (GAIL)", "gail", "value"),
)


def across_seeds(files: list[Path]) -> None:
    """Per task and score, tau-b of the level means (per-trajectory tau-b) for each file written by a run of this
    script, one training seed each."""
    saved = [json.loads(f.read_text()) for f in files]
    seeds = [next((a["run"].rsplit("-s", 1)[-1] for t in d["tasks"].values() for a in t.values()), "?") for d in saved]
    print("\n| task | score | " + " | ".join(f"seed {s}" for s in seeds) + " |")
    print("|---|---|" + "---|" * len(seeds))
    for task in TASKS:
        for label, algorithm, key in SCORED:
            cells = []
            for d in saved:
                r = d["tasks"].get(task, {}).get(algorithm, {}).get("ranking", {}).get(key)
                cells.append(
                    "-"
                    if not r or r["kendall_tau_b"] is None
                    else f"{r['kendall_tau_b_of_level_means']:.2f} ({r['kendall_tau_b']:.2f})"
                )
            if any(c != "-" for c in cells):
                print(f"| {task} | {label} | " + " | ".join(cells) + " |")


def timing(root: Path, seed: int = 0, levels: int = 5, per_level: int = 20, rounds: int = 3) -> dict | None:
    """Seconds to score 100 TraceLines trajectories with the AIRL run (replay and networks included); None: no run."""
    from fastrl.assess.report import score_files, trajectory_files
    from fastrl.runner.score.assessment import load_scorer

    run = irl_run("tracelines", "airl", root, seed)
    if run is None:
        return None
    cohort = cohort_dir("tracelines", levels, per_level)
    scorer, _ = load_scorer(run, None)
    files = trajectory_files([cohort])
    best, steps = float("inf"), 0
    for _ in range(rounds):
        t0 = time.perf_counter()
        scored, problems = score_files(scorer, files)
        best = min(best, time.perf_counter() - t0)
        steps = sum(len(s.time) for s in scored)
    return {"trajectories": len(files), "samples": steps, "seconds": best, "samples_per_s": steps / best}


def main() -> None:
    """Score every task's cohort, print the tables and the timing, write JSON."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", nargs="+", default=list(TASKS), choices=TASKS)
    ap.add_argument("--levels", type=int, default=5)
    ap.add_argument("--per-level", type=int, default=10)
    ap.add_argument("--timing-only", action="store_true")
    ap.add_argument("--out", type=Path, default=Path("docs/assess_cohort.json"))
    ap.add_argument(
        "--irl-root", type=Path, default=Path("runs/bench-irl"), help="where bench/irl_tasks.py wrote its runs"
    )
    ap.add_argument("--seed", type=int, default=0, help="the inverse-RL runs' training seed")
    ap.add_argument(
        "--across",
        nargs="+",
        type=Path,
        metavar="JSON",
        help="only print tau-b of the level means per seed from files earlier calls wrote (--out)",
    )
    args = ap.parse_args()
    if args.across:
        across_seeds(args.across)
        return
    print(f"# {machine_line()}")
    results = {}
    if not args.timing_only:
        for task in args.tasks:
            results[task] = score_task(task, args.levels, args.per_level, args.irl_root, args.seed)
            table(task, results[task])
    t = timing(args.irl_root, args.seed)
    if t is None:
        print(f"\nno TraceLines AIRL run under {args.irl_root} for seed {args.seed}: scoring time not measured")
    else:
        print(
            f"\nscoring {t['trajectories']} TraceLines trajectories ({t['samples']} samples, replay and networks "
            f"included): {t['seconds']:.2f} s ({t['samples_per_s']:,.0f} samples/s)"
        )
    summary = {
        task: {
            alg: {"run": r["run"], "ranking": r["report"]["ranking"], "groups": r["report"]["groups"]}
            for alg, r in res.items()
        }
        for task, res in results.items()
    }
    saved = json.loads(args.out.read_text()) if args.out.exists() else {"tasks": {}}
    saved["tasks"].update(summary)
    if t is not None:
        saved["timing"] = t
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(saved, indent=2))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
