"""Whom does `fastrl assess` learn from? The skill levels of the best K under each `--by`, per trainee family.

    python bench/who_is_learned_from.py --tasks tracelines imagecentring periscoping
    python bench/who_is_learned_from.py --root runs/bench-validity --json docs/who_is_learned_from.json

The protocol learns from the best K recordings of a cohort by a rule that sees no labels (`--by`). Each family's
5 x 10 cohort of bench/validity.py (written there once, reused here) is scored by replay once (twice for `motion`);
for each rule the mean skill level of its best K and how many of them are at the top level are printed (5.0 and K:
only experts).
A rule that lets novices in teaches the learned reward their deficit as expert behaviour.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

from common import machine_line
from validity import ROOT, cohort


def chosen_levels(task: str, family: str, root: Path, top: int) -> dict[str, list[int]]:
    """The skill levels of the best `top` of the family's cohort under each ranking rule, best first."""
    from fastrl.runner.chosen import BY, rank_key, rank_recordings
    from fastrl.spec import load_spec

    spec = load_spec(f"specs/{task}.yaml")
    ranked, _ = rank_recordings(spec, [cohort(task, family, root)], "time")
    scores = [s for s, _ in ranked]
    levels = {}
    for by in BY:
        if by == "motion":  # ranks need the whole cohort's motion under its best `top`'s
            best = [s for s, _ in rank_recordings(spec, [cohort(task, family, root)], by, top)[0][:top]]
        else:
            best = sorted(scores, key=lambda s: rank_key(s, by))[:top]
        levels[by] = [int(s.skill) for s in best]
    return levels


def main() -> None:
    from fastrl.data.families import FAMILIES

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="+", default=["tracelines"])
    parser.add_argument("--families", nargs="+", default=[*FAMILIES, "mixed"])
    parser.add_argument("--top", type=int, default=10)
    parser.add_argument("--root", type=Path, default=ROOT)
    parser.add_argument("--json", type=Path, default=Path("docs/who_is_learned_from.json"))
    args = parser.parse_args()
    started = {"machine": machine_line(), "utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "top": args.top}
    print(f"# {started['utc']} UTC, {started['machine']}", flush=True)
    print(f"mean level of the best {args.top} / how many at level 5, per ranking rule (--by)")
    rows = []
    for task in args.tasks:
        for family in args.families:
            levels = chosen_levels(task, family, args.root, args.top)
            rows.append({"task": task, "family": family, "levels": levels})
            cells = "  ".join(f"{by} {sum(v) / len(v):.1f}/{v.count(5)}" for by, v in levels.items())
            print(f"{task:13s} {family:14s} {cells}", flush=True)
        worst = {
            by: min(sum(r["levels"][by]) / args.top for r in rows if r["task"] == task) for by in rows[-1]["levels"]
        }
        print(f"{task:13s} {'worst family':14s} " + "  ".join(f"{by} {v:.1f}" for by, v in worst.items()))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({**started, "rows": rows}, indent=1))
    print(f"# ended {time.strftime('%H:%M', time.gmtime())} UTC, {machine_line()}")


if __name__ == "__main__":
    main()
