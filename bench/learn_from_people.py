"""Learning from people: the paper's protocol on a cohort without actions, next to the same with the true actions.

    python bench/learn_from_people.py --tasks tracelines                    # one FAST task, without vs with actions
    python bench/learn_from_people.py                                       # all three FAST tasks
    python bench/learn_from_people.py --tasks --liver                       # the liver tour only
    python bench/learn_from_people.py --tasks --recovery tracelines         # recovered-action accuracy only
    python bench/learn_from_people.py --from-json docs/learn_from_people.json   # re-print earlier results

Per FAST task: a cohort (`fastrl cohort SPEC --levels 5 --per-level 10`, seed 0, under runs/bench-people/<task>/),
then `fastrl assess COHORT --spec SPEC --top 10` (AIRL, PPO generator, --timesteps generator steps with periodic
evaluation and an early stop once an evaluation completes every subtask): once with the actions removed (recovered
from the states) and once with the true actions kept. Prints Kendall tau-b and Spearman's rho of the heuristic
return, the learned reward r_psi and the learned value V against the skill labels over the 50 trajectories, the
learned policy's subtask completion (eval.json, 20 seeds), and the recovered-action agreement on the 10 chosen
(exact-match rate). Liver tour: 100 procedures (5 x 20), the best 10 without actions, Spearman of learned reward and
value against economy and safety, on the whole --liver-timesteps budget (no early stop: stopped at its first tour,
100k-250k steps, the critic is too young to rank). Writes docs/learn_from_people.json.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import platform
import time
from pathlib import Path

from common import machine_line

TASKS = ("imagecentring", "periscoping", "tracelines")
ROOT = Path("runs/bench-people")  # --root changes it


def cohort(task: str, levels: int, per_level: int) -> tuple[Path, Path]:
    """(with actions, without actions) folders of the task's cohort, generated once."""
    from fastrl.data.cohort import make_cohort
    from fastrl.data.trajectory import Trajectory
    from fastrl.spec import load_spec

    spec = load_spec(f"specs/{task}.yaml")
    full, bare = ROOT / task / f"cohort-{levels}x{per_level}", ROOT / task / f"cohort-{levels}x{per_level}-states"
    if len(list(bare.glob("*.npz"))) < levels * per_level:
        full.mkdir(parents=True, exist_ok=True)
        bare.mkdir(parents=True, exist_ok=True)
        for traj in make_cohort(spec, levels, per_level, seed=0):
            traj.save(full / f"{traj.meta['subject']}.npz")
            Trajectory(traj.time, traj.portal, traj.meta).save(bare / f"{traj.meta['subject']}.npz")
    return full, bare


def overrides(timesteps: int, seed: int, stop: bool = True) -> list[str]:
    """The spec changes of one protocol run; `stop`: end at the first evaluation that completes every subtask."""
    return [
        f"train.timesteps={timesteps}",
        f"train.seed={seed}",
        "evaluate.periodic_every=50000",
        "evaluate.periodic_episodes=10",
        *(["evaluate.stop_at_subtasks=1.0"] if stop else []),
        "evaluate.image_every=8",
        "evaluate.record_episodes=2",
        "train.checkpoint_every=50000",
    ]


def agreement_on_best(task: str, run: Path, full: Path) -> dict:
    """Recovered vs true actions on the recordings the protocol learned from."""
    from fastrl.data.inverse import ActionRecovery, agreement
    from fastrl.data.trajectory import Trajectory
    from fastrl.env import FastEnv
    from fastrl.spec import load_spec

    spec = load_spec(f"specs/{task}.yaml")
    rec = ActionRecovery(FastEnv(spec))
    steps, matched = 0, 0.0
    for f in sorted((run / "best").glob("*.npz")):
        true = Trajectory.load(full / f.name)
        got = rec.recover(Trajectory.load(f))
        a = agreement(true.actions, got.actions, spec.actions.mode)
        steps += a["steps"]
        matched += a["exact_match"] * a["steps"]
    return {"steps": steps, "exact_match": matched / max(steps, 1)}


TRACKER_SD = (0.1, 0.1, 0.2, 0.3, 0.3)  # deg, deg, mm, deg, deg: noise added to the portal coordinates


def recovery_table(task: str, full: Path) -> dict:
    """Recovered-action agreement on the whole cohort: as recorded, resampled 20 -> 50 -> 20 Hz, and that plus
    Gaussian tracker noise (TRACKER_SD) at 50 Hz."""
    import numpy as np

    from fastrl.data.inverse import ActionRecovery, agreement, to_control_rate
    from fastrl.data.trajectory import Trajectory
    from fastrl.env import FastEnv
    from fastrl.spec import load_spec

    spec = load_spec(f"specs/{task}.yaml")
    rec, rng = ActionRecovery(FastEnv(spec)), np.random.default_rng(0)
    sd = np.radians(TRACKER_SD) * np.array([1, 1, 0, 1, 1]) + np.array([0, 0, TRACKER_SD[2] / 1000, 0, 0])
    out = {}
    for label in ("as recorded", "50 Hz", "50 Hz + tracker noise"):
        steps, matched, t0 = 0, 0.0, time.perf_counter()
        for f in sorted(full.glob("*.npz")):
            t = Trajectory.load(f)
            x = Trajectory(t.time, t.portal, t.meta)
            if label != "as recorded":
                tt = np.arange(0, t.time[-1] + 1e-9, 0.02)
                q = np.column_stack([np.interp(tt, t.time, t.portal[:, j]) for j in range(5)])
                q = q + (rng.normal(0, 1, q.shape) * sd if "noise" in label else 0.0)
                x = to_control_rate(Trajectory(tt, q, t.meta), spec.episode.control_hz)
            a = agreement(t.actions, rec.recover(x).actions, spec.actions.mode)
            steps, matched = steps + a["steps"], matched + a["exact_match"] * a["steps"]
        out[label] = {"steps": steps, "exact_match": matched / steps, "seconds": time.perf_counter() - t0}
    return out


def protocol(task: str, inputs: Path, keep: bool, args) -> dict:
    """One `fastrl assess` run and its figures."""
    from rich.console import Console

    from fastrl.runner.protocol import run_protocol

    t0 = time.perf_counter()
    done = run_protocol(
        [inputs],
        Path(f"specs/{task}.yaml"),
        args.top,
        "heuristic",
        "airl",
        # the liver runs its budget: stopped at its first tour (100k-250k steps) the critic is too young to rank
        overrides(args.liver_timesteps, args.seed, stop=False)
        if task == "liver_tour"
        else overrides(args.timesteps, args.seed),
        ROOT / ("with-actions" if keep else "without-actions"),
        console=Console(stderr=True),
        progress=False,
        pictures=False,
        keep_actions=keep,
    )
    seconds = time.perf_counter() - t0
    report = done.assessment.report
    ev = json.loads((done.learned[0] / "eval.json").read_text())["agent"]
    meta = json.loads((done.learned[0] / "meta.json").read_text())
    out = {
        "run": str(done.run),
        "chosen": [r["file"] for r in done.chosen],
        "seconds": seconds,
        "trained_timesteps": meta.get("trained_timesteps"),
        "policy_subtasks": ev["subtasks_completed"],
        "policy_success": ev["success_rate"],
        "ranking": {
            k: {"kendall_tau_b": r["kendall_tau_b"], "spearman": r["spearman"]}
            for k, r in report["ranking"].items()
            if k in ("heuristic", "reward", "value")
        },
    }
    if task == "liver_tour":
        from fastrl.runner.study import correlation

        rows = report["trajectories"]
        out["table3"] = {
            f"{k}-{m}": correlation([r[k + "_raw"] for r in rows], [r[m] for r in rows])
            for k in ("heuristic", "reward", "value")
            for m in ("economy", "safety")
        }
    return out


def show(results: dict) -> None:
    """The side-by-side table."""
    print("| task | actions | heuristic tau-b / rho | reward tau-b / rho | value tau-b / rho | policy subtasks |")
    print("|---|---|---|---|---|---|")
    for task, by in results["tasks"].items():
        for variant, r in by.items():
            if "ranking" not in r:  # recovery and the per-seed extras
                continue
            cells = [
                f"{r['ranking'][k]['kendall_tau_b']:.2f} / {r['ranking'][k]['spearman']:.2f}"
                if k in r["ranking"] and r["ranking"][k]["kendall_tau_b"] is not None
                else "-"
                for k in ("heuristic", "reward", "value")
            ]
            print(f"| {task} | {variant} | {' | '.join(cells)} | {r['policy_subtasks']:.1%} |")
        if "recovery" in by:
            print(f"  recovered actions on the 10 chosen: {by['recovery']['exact_match']:.1%} exact match")
    for task, rows in results.get("recovery", {}).items():
        cells = ", ".join(f"{k}: {v['exact_match']:.1%} of {v['steps']} steps" for k, v in rows.items())
        print(f"recovered actions, {task} cohort (exact match): {cells}")
    liver = results.get("liver")
    if liver:
        print("liver tour, best 10 of 100 without actions: Spearman rho (p)")
        for k, v in liver["table3"].items():
            print(f"  {k}: {v['rho']:.2f} ({v['p']:.1g})" if v["rho"] is not None else f"  {k}: -")


def main() -> None:
    """Run what is asked and print the tables."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", nargs="*", default=list(TASKS))
    ap.add_argument("--variants", nargs="*", default=["without", "with"])
    ap.add_argument("--recovery", nargs="*", default=[], help="recovered-action agreement on these tasks' cohorts")
    ap.add_argument("--liver", action="store_true", help="also the liver tour (100 procedures, best 10)")
    ap.add_argument("--timesteps", type=int, default=600000, help="generator step cap per FAST run")
    ap.add_argument("--liver-timesteps", type=int, default=300000)
    ap.add_argument("--top", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("docs/learn_from_people.json"))
    ap.add_argument("--from-json", type=Path)
    ap.add_argument("--root", type=Path, default=ROOT)
    args = ap.parse_args()
    globals()["ROOT"] = args.root
    if args.from_json:
        show(json.loads(args.from_json.read_text()))
        return
    results = json.loads(args.out.read_text()) if args.out.exists() else {"tasks": {}}
    results["machine"] = {"platform": platform.platform(), "cpus": os.cpu_count(), "load": os.getloadavg()}
    print(machine_line())
    for task in args.tasks:
        full, bare = cohort(task, 5, 10)
        by = results["tasks"].setdefault(task, {})
        for variant in args.variants:
            by[variant] = protocol(task, bare if variant == "without" else full, variant == "with", args)
            if variant == "without":
                by["recovery"] = agreement_on_best(task, Path(by[variant]["run"]), full)
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(json.dumps(results, indent=2))
    if args.recovery:
        for task in args.recovery:
            results.setdefault("recovery", {})[task] = recovery_table(task, cohort(task, 5, 10)[0])
        args.out.write_text(json.dumps(results, indent=2))
    if args.liver:
        from fastrl.data.cohort import make_cohort
        from fastrl.data.trajectory import Trajectory
        from fastrl.spec import load_spec

        bare = ROOT / "liver_tour" / "cohort-5x20-states"
        if len(list(bare.glob("*.npz"))) < 100:
            bare.mkdir(parents=True, exist_ok=True)
            for traj in make_cohort(load_spec("specs/liver_tour.yaml"), 5, 20, seed=0):
                Trajectory(traj.time, traj.portal, traj.meta).save(bare / f"{traj.meta['subject']}.npz")
        results["liver"] = protocol("liver_tour", bare, False, args)
        args.out.write_text(json.dumps(results, indent=2))
    show(results)


if __name__ == "__main__":
    main()
