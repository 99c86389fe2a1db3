"""Do the learned scores hold on trainees of every deficit family? The paper's protocol per family, beside the clock.

    python bench/validity.py --tasks tracelines --seeds 0                       # every family, one seed
    python bench/validity.py --tasks tracelines periscoping imagecentring --seeds 0 1 2
    python bench/validity.py --tasks triangulation --families classic flow speed corrections
    python bench/validity.py --degrade drift jitter slowed                      # copies less the family's own
    python bench/validity.py --from-json docs/validity.json                     # re-print earlier results

For each task and each trainee family (fastrl.data.families; `mixed`: the acted families, each subject its own mix;
`mixed_overlays`: the same over the five overlays on the recordings, as a cohort built outside the project may be), a
cohort of 5 levels x 10 subjects is written without actions (seed 0, under ROOT/TASK/FAMILY/cohort), then
`fastrl assess COHORT --spec specs/TASK.yaml --top 10` (AIRL, the spec's generator; `train.seed` = each --seeds)
learns from the best 10 and scores all 50. Printed per task, family and seed: Kendall tau-b against the skill labels
of the learned reward, value and motion, the heuristic return, the stopwatch (time), the path length and the
subtasks, with the sign that ranks. The protocol sees no labels and no family. With --degrade, the ranking prior's
degraded copies of the best recordings carry those overlays less the scored family's own, so an overlay family is
never ranked by copies made its way. Which rows chose which shipped setting is written beside the table in
RESULTS.md (validity): a family whose row chose a setting is not held out for it. Writes --json (docs/validity.json).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

from common import machine_line

SCORES = ("reward", "value", "motion", "heuristic", "time", "path_length", "subtasks")
ROOT = Path("runs/bench-validity")


MIXES = ("mixed", "mixed_overlays")  # cohorts whose subjects each draw their own mix of several families


def drawn_from(family: str) -> tuple[str, ...]:
    """The families a cohort's subjects draw from: `mixed` the acted ones, `mixed_overlays` the overlays."""
    from fastrl.data.families import FAMILIES

    if family in MIXES:
        return tuple(f for f in FAMILIES if bool(FAMILIES[f].overlay) == (family == "mixed_overlays"))
    return (family,)


def cohort(task: str, family: str, root: Path) -> Path:
    """The family's 5 x 10 cohort of the task without actions, written once (again when the task has changed)."""
    from fastrl.data.cohort import make_cohort
    from fastrl.data.trajectory import Trajectory
    from fastrl.spec import load_spec, task_hash

    spec = load_spec(f"specs/{task}.yaml")
    out = root / task / family / "cohort"
    files = sorted(out.glob("*.npz"))
    if len(files) == 50 and Trajectory.load(files[0]).meta.get("task_hash") == task_hash(spec):
        return out
    out.mkdir(parents=True, exist_ok=True)
    for traj in make_cohort(spec, 5, 10, seed=0, families=drawn_from(family)):
        bare = Trajectory(traj.time, traj.portal, traj.meta, instruments=traj.instruments, bodies=traj.bodies)
        bare.save(out / f"{traj.meta['subject']}.npz")
    return out


def left_out(family: str, degrade: list[str] | None) -> list[str]:
    """The --set of the ranking's degraded copies without the overlays of the family or its mix (leave one out)."""
    from fastrl.data.families import FAMILIES

    if degrade is None:
        return []
    own = {FAMILIES[f].overlay for f in drawn_from(family)}
    return [f"irl.discriminator.ranking_degraded=[{', '.join(d for d in degrade if d not in own)}]"]


def measure(task: str, family: str, seed: int, root: Path, sets: tuple[str, ...] = (), make=None) -> dict:
    """One protocol run on the family's cohort (made by `make`, else this bench's): tau-b of every score, whom it
    learned from, and its wall time."""
    from rich.console import Console

    from fastrl.runner.protocol import run_protocol

    folder = (make or cohort)(task, family, root)
    t0 = time.perf_counter()
    done = run_protocol(
        [folder],
        Path(f"specs/{task}.yaml"),
        top=10,
        overrides=[*sets, f"train.seed={seed}"],
        root=root / task / family / "runs",
        console=Console(stderr=True, quiet=True),
        progress=False,
        pictures=False,
    )
    ranking = done.assessment.report["ranking"]
    taus = {k: ranking[k]["kendall_tau_b"] for k in SCORES if k in ranking}
    return {
        "task": task,
        "family": family,
        "seed": seed,
        "sets": list(sets),
        "tau_b": taus,
        "chosen_level": sum(c["skill"] for c in done.chosen) / len(done.chosen),  # whom it learned from (5: experts)
        "steps": [json.loads((d / "meta.json").read_text()).get("trained_timesteps") for d in done.learned],
        "seconds": time.perf_counter() - t0,
    }


def table(rows: list[dict]) -> str:
    """Markdown table: one row per task, family and seed; a learned score in bold where it ties or beats the clock."""
    head = "| task | family | seed | " + " | ".join(SCORES) + " | level learned from | wall |"
    lines = [head, "|" + "---|" * (len(SCORES) + 5)]
    for r in rows:
        t = r["tau_b"]
        simple = max(t.get("time") or -1, t.get("path_length") or -1)
        cells = []
        for k in SCORES:
            v = t.get(k)
            text = "-" if v is None else f"{v:.2f}"
            cells.append(f"**{text}**" if k in ("reward", "value") and v is not None and v >= simple else text)
        level = f"{r['chosen_level']:.1f}" if "chosen_level" in r else "-"
        row = [r["task"], r["family"], str(r["seed"]), *cells, level, f"{r['seconds']:.0f} s"]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def main() -> None:
    from fastrl.data.families import FAMILIES

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="+", default=["tracelines"])
    parser.add_argument("--families", nargs="+", default=[*FAMILIES, *MIXES])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--root", type=Path, default=ROOT)
    parser.add_argument("--set", dest="sets", action="append", default=[], help="spec change, as fastrl's --set")
    parser.add_argument(
        "--degrade",
        nargs="*",
        help="the ranking's degraded copies carry these overlays, less the scored family's own (leave-one-family-out)",
    )
    parser.add_argument("--json", type=Path, default=Path("docs/validity.json"))
    parser.add_argument("--from-json", type=Path, help="print the table of an earlier run and stop")
    args = parser.parse_args()
    if args.from_json:
        print(table(json.loads(args.from_json.read_text())["rows"]))
        return
    unknown = [f for f in args.families if f not in FAMILIES and f not in MIXES]
    if unknown:
        parser.error(f"unknown family {unknown[0]}: choose from {', '.join([*FAMILIES, *MIXES])}")
    measure_all(args, lambda family: (*args.sets, *left_out(family, args.degrade)))


def measure_all(args, sets_of, make=None) -> None:
    """Every task, family and seed of the parsed `args` (spec changes `sets_of(family)`): printed as each ends, the
    rows written to args.json after each, the table at the end."""
    started = {"machine": machine_line(), "utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "sets": args.sets}
    print(f"# {started['utc']} UTC, {started['machine']}", flush=True)
    rows = []
    for task in args.tasks:
        for family in args.families:
            for seed in args.seeds:
                rows.append(measure(task, family, seed, args.root, sets_of(family), make))
                t = rows[-1]["tau_b"]
                print(
                    f"{task} {family} s{seed}: "
                    + ", ".join(f"{k} {t[k]:.2f}" for k in t if t[k] is not None)
                    + f"; {rows[-1]['seconds']:.0f} s, steps {rows[-1]['steps']}",
                    flush=True,
                )
                args.json.parent.mkdir(parents=True, exist_ok=True)
                args.json.write_text(json.dumps({**started, "rows": rows}, indent=1))
    print(f"# ended {time.strftime('%H:%M', time.gmtime())} UTC, {machine_line()}")
    print(table(rows))


if __name__ == "__main__":
    main()
