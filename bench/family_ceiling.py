"""How far can a trainee family's skill labels be read at all? Kinematic summaries, each alone and all together.

    python bench/family_ceiling.py --tasks tracelines imagecentring periscoping
    python bench/family_ceiling.py --tasks tracelines --root runs/bench-validity --json docs/family_ceiling.json
    python bench/family_ceiling.py --outside        # the cohorts of bench/outside_cohorts.py instead

For each task and family, the 5 x 10 cohort of bench/validity.py (written there if missing, seed 0, without actions)
is replayed as `fastrl assess` replays it, and each trajectory is summarised by what a rater or a tracker could
measure: duration, camera path length, subtasks done, mean linear and angular speed of the camera, mean distance
error, mean off-centre of the target in the image, horizon error, contacts and jerk. Printed per family, Kendall tau-b
against the labels of:
- each summary alone, signed so that higher ranks better; the best of them is chosen with the labels, so it is an
  optimistic ceiling for any single metric;
- a supervised scorer: a ridge regression of the label on all the summaries (standardised), its predictions 5-fold
  cross-validated (folds by subject, every level in each). It sees labels, which `fastrl assess` never does.
- two that see no label, as the learned scores do not, both from the best 10 by the protocol's rule (the recordings
  `fastrl assess` learns from): the motion's typicality, how far a trajectory's duration, path length, speed, turn
  rate and jerk lie from theirs, each in units of their spread there, summed in log; and the motion's likelihood,
  the log-density of each of its steps' motion (speed, turn rate and their changes since the step before, in log)
  under a Gaussian kernel density of their steps', summed over the trajectory (`fastrl assess`'s motion score,
  which it gives on one-scope tasks only).
A family on which even the supervised scorer stays under 0.8 cannot meet issue 43's bar (learned reward and value
>= 0.8) through what these summaries hold: its labels say less about the trajectories than the bar asks of a score.
A score without ties reaches at most 0.90 on a 5 x 10 cohort (the labels tie within a level).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

import numpy as np
from common import machine_line
from validity import ROOT, cohort

FOLDS = 5
RIDGE = 1.0  # on standardised summaries; 0.1 or 10 move the fits of seven TraceLines families by 0.04 at most


def summaries(scored, obs: np.ndarray, own: int, columns: dict[str, list[int]]) -> dict[str, float]:
    """What a rater or a tracker could measure of one replayed trajectory, each signed so that higher is better."""
    own_obs = obs[:own]

    def mean_norm(term: str, first: int | None = None) -> float:
        cols = columns[term][:first] if first else columns[term]
        return float(np.linalg.norm(own_obs[:, cols], axis=1).mean())

    s = scored.scores
    return {
        "time": -s["time"],
        "path_length": -s["path_length"],
        "subtasks": s["subtasks"],
        "speed": mean_norm("tip_vel"),
        "turn_rate": mean_norm("tip_quat_rate"),
        "distance_error": -mean_norm("distance_error"),
        "off_centre": -mean_norm("target_in_camera", 2),
        "horizon_error": -mean_norm("horizon_error"),
        "contacts": -float(own_obs[:, columns["contact"]].sum()),
        "jerk": s["smoothness"],
    }


MOTION = ("time", "path_length", "speed", "turn_rate", "jerk")
BEST = 10  # the protocol's --top


def best_ten(rows: list[dict]) -> list[int]:
    """The recordings `fastrl assess` learns from: the most subtasks done, then the shortest (the stopwatch)."""
    return sorted(range(len(rows)), key=lambda i: (rows[i]["subtasks"], rows[i]["time"]), reverse=True)[:BEST]


def typicality(rows: list[dict]) -> np.ndarray:
    """Label-free: minus how far each trajectory's motion summaries lie from the best 10's, in units of their spread
    there (at least 5% of the cohort's), summed in log; higher is more like them."""
    x = np.array([[r[k] for k in MOTION] for r in rows], float)
    best = x[best_ten(rows)]
    spread = np.maximum(best.std(0), 0.05 * x.std(0) + 1e-12)
    return -np.log1p(np.abs((x - np.median(best, 0)) / spread)).sum(1)


def motion_likelihood(steps: list[np.ndarray], own: list[int], best: list[int]) -> np.ndarray:
    """Label-free: each trajectory's motion likelihood (fastrl.assess.motion, the score `fastrl assess` reports)
    under the best 10's own steps."""
    from fastrl.assess.motion import MotionModel

    model = MotionModel.fit([steps[i][: own[i]] for i in best])
    return np.array([model.log_likelihood(s) for s in steps])


def observation_columns(spec) -> dict[str, list[int]]:
    """Each observation term's columns."""
    from fastrl.spec.columns import column_terms

    names = column_terms(spec)
    return {n: [i for i, m in enumerate(names) if m == n] for n in dict.fromkeys(names)}


def tau(x, labels) -> float | None:
    """Kendall tau-b of x against the labels (None where x is constant)."""
    from scipy.stats import kendalltau

    x = np.asarray(x, float)
    return None if np.ptp(x) == 0 else float(kendalltau(x, labels, variant="b").statistic)


def supervised(features: np.ndarray, labels: np.ndarray) -> float:
    """Tau-b of a ridge regression of the labels on the standardised features, predicted fold by fold."""
    spread = features.std(0)
    x = (features - features.mean(0)) / np.where(spread > 0, spread, 1.0)
    x = np.column_stack([x, np.ones(len(x))])
    folds = np.arange(len(labels)) % FOLDS  # files in subject order: every level in every fold
    predicted = np.empty(len(labels))
    for k in range(FOLDS):
        fit = folds != k
        w = np.linalg.solve(x[fit].T @ x[fit] + RIDGE * np.eye(x.shape[1]), x[fit].T @ labels[fit])
        predicted[~fit] = x[~fit] @ w
    return tau(predicted, labels)


def family_row(task: str, family: str, root: Path, make=cohort) -> dict:
    """Every summary's tau-b, the best single one, and the supervised scorer's, for one family's cohort (made by
    `make`: bench/validity.py's or bench/outside_cohorts.py's)."""
    from fastrl.assess.motion import step_motion
    from fastrl.assess.scoring import Scorer
    from fastrl.spec import load_spec

    spec = load_spec(f"specs/{task}.yaml")
    scorer, columns = Scorer(spec), observation_columns(spec)
    motion = (columns["tip_vel"], columns["tip_quat_rate"])  # the scope's, also where fastrl scores no motion
    rows, labels, steps, own = [], [], [], []
    for f in sorted(make(task, family, root).glob("*.npz")):
        traj = scorer.load_file(f)
        scored, obs = scorer.replayed(traj, f.stem)
        own.append(min(len(traj.time), len(obs)))
        rows.append(summaries(scored, obs, own[-1], columns))
        labels.append(scored.skill)
        steps.append(step_motion(obs, motion))
    labels = np.asarray(labels, float)
    taus = {k: tau([r[k] for r in rows], labels) for k in rows[0]}
    usable = {k: t for k, t in taus.items() if t is not None}
    best = max(usable, key=lambda k: abs(usable[k]))
    features = np.array([[r[k] for k in usable] for r in rows])
    return {
        "task": task,
        "family": family,
        "tau_b": taus,
        "best_single": best,
        "best_single_tau_b": abs(usable[best]),
        "supervised_tau_b": supervised(features, labels),
        "typicality_tau_b": tau(typicality(rows), labels),
        "motion_likelihood_tau_b": tau(motion_likelihood(steps, own, best_ten(rows)), labels),
    }


def main() -> None:
    from fastrl.data.families import FAMILIES, WITH_INSTRUMENTS

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="+", default=["tracelines"])
    parser.add_argument("--families", nargs="+", default=[*FAMILIES, "mixed"])
    parser.add_argument("--root", type=Path, default=ROOT)
    parser.add_argument("--json", type=Path, help="write the rows here (docs/family_ceiling.json)")
    parser.add_argument("--outside", action="store_true", help="bench/outside_cohorts.py's kinds and cohorts")
    args = parser.parse_args()
    make = cohort
    if args.outside:
        import outside_cohorts

        make, args.root = outside_cohorts.cohort, outside_cohorts.ROOT
        args.families = [*outside_cohorts.KINDS, "mix"]
    print(f"# {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC, {machine_line()}", flush=True)
    print("| task | family | time | path length | best single summary | supervised | typicality | motion likelihood |")
    print("|---|---|---|---|---|---|---|---|")
    rows = []
    for task in args.tasks:
        two_hands = task == "triangulation"
        for family in args.families:
            if two_hands and family not in WITH_INSTRUMENTS:
                continue
            r = family_row(task, family, args.root, make)
            rows.append(r)
            t = r["tau_b"]
            print(
                f"| {task} | {family} | {t['time']:.2f} | {t['path_length'] or 0:.2f} | "
                f"{r['best_single']} {r['best_single_tau_b']:.2f} | {r['supervised_tau_b']:.2f} | "
                f"{r['typicality_tau_b']:.2f} | {r['motion_likelihood_tau_b']:.2f} |",
                flush=True,
            )
    if args.json:
        args.json.write_text(json.dumps({"machine": machine_line(), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
