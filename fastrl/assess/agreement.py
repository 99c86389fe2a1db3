"""Scores learned on several seeds as one: each trajectory's mean and spread, the seeds' agreement, the agreement of
the learned scores with the simple metrics, and the warnings a reader needs before trusting them."""

from __future__ import annotations

from itertools import combinations

import numpy as np

from .ranking import _tau_of, rank_correlations, subject_table
from .scoring import HIGHER_IS_BETTER

SIMPLE = ("time", "path_length", "subtasks")  # what a stopwatch, a tracker and a checklist give
SEEDS_AGREE = 0.6  # mean Kendall tau between the seeds' rankings below this: the seeds disagree
# a learned score whose ranking agrees with the motion's below this is warned of: over 62 cohorts (fastrl's families,
# kinds nobody modelled) that agreement followed the reward's own tau-b at Spearman 0.82 (RESULTS: the motion's
# likelihood); the same bar as the seeds'
MOTION_AGREES = SEEDS_AGREE
UNLIKE_MOTION = "ranks unlike the motion"


def _column(report: dict, key: str, files: list[str]) -> np.ndarray:
    """One score of every file (normalised where the report normalises it, else raw), in `files` order."""
    by_file = {r["file"]: r for r in report["trajectories"]}
    return np.array([np.nan if by_file[f].get(key) is None else float(by_file[f][key]) for f in files])


def _ranked(report: dict, key: str, files: list[str]) -> np.ndarray:
    """The raw score (what rankings use) of every file, better higher."""
    col = _column(report, key + "_raw" if any(key + "_raw" in r for r in report["trajectories"]) else key, files)
    return col if HIGHER_IS_BETTER[key] else -col


def _tau(a: np.ndarray, b: np.ndarray) -> float | None:
    """Kendall tau-b over the files both score; None where undefined."""
    keep = np.isfinite(a) & np.isfinite(b)
    if keep.sum() < 3:
        return None
    t = _tau_of(a[keep], b[keep])
    return None if not np.isfinite(t) else t


def unlike_motion(ranked: dict[str, np.ndarray], motion: np.ndarray) -> list[str]:
    """A warning for each learned score (higher better) whose ranking agrees with the motion's at Kendall tau below
    MOTION_AGREES: a label-free sign that it reads the levels badly."""
    warnings = []
    for key, x in ranked.items():
        t = _tau(np.asarray(x, float), np.asarray(motion, float))
        if t is not None and t < MOTION_AGREES:
            warnings.append(
                f"{key}: {UNLIKE_MOTION} (Kendall tau {t:.2f} with it, below {MOTION_AGREES}): on labelled cohorts "
                "such a score read the levels badly; check it before use"
            )
    return warnings


def _z(x: np.ndarray) -> np.ndarray:
    """Standardised scores (a seed's ranking weight in the mean, whatever its scale)."""
    sd = np.nanstd(x)
    return (x - np.nanmean(x)) / sd if sd > 0 else np.zeros_like(x)


def combine(reports: list[dict], seeds: list[int], learned: tuple[str, ...] = ("reward", "value", "motion")) -> dict:
    """One report from per-seed reports of the same files: the learned scores as mean ± sd over seeds (the ranking
    uses the mean of each seed's standardised raw score), the seeds' agreement, the agreement of each learned
    score with the simple metrics, and warnings."""
    first = reports[0]
    files = [r["file"] for r in first["trajectories"]]
    learned = tuple(k for k in learned if k in first["scores"])
    rows = [dict(r) for r in first["trajectories"]]
    agreement, against, ensembles = {}, {}, {}
    warnings = [w for w in first["warnings"] if UNLIKE_MOTION not in w]  # judged below on the seeds' mean instead
    for key in learned:
        shown = np.array([_column(rep, key, files) for rep in reports])
        ranked = np.array([_ranked(rep, key, files) for rep in reports])
        ensemble = ensembles[key] = np.mean([_z(r) for r in ranked], axis=0)
        normalised = any(key + "_raw" in r for r in first["trajectories"])  # motion is raw only
        raw = np.nanmean([_column(rep, key + "_raw" if normalised else key, files) for rep in reports], 0)
        for row, mean, sd, r, e in zip(rows, np.nanmean(shown, 0), np.nanstd(shown, 0), raw, ensemble):
            row[key], row[key + "_sd"], row[key + "_z"] = map(_finite, (mean, sd, e))
            if normalised:
                row[key + "_raw"] = _finite(r)
        pairs = [_tau(ranked[i], ranked[j]) for i, j in combinations(range(len(reports)), 2)]
        pairs = [p for p in pairs if p is not None]
        agreement[key] = {
            "mean_tau": float(np.mean(pairs)) if pairs else None,
            "min_tau": float(np.min(pairs)) if pairs else None,
        }
        against[key] = {s: _tau(ensemble, _ranked(first, s, files)) for s in SIMPLE if s in first["scores"]}
        if agreement[key]["mean_tau"] is not None and agreement[key]["mean_tau"] < SEEDS_AGREE:
            warnings.append(
                f"{key}: the {len(reports)} seeds disagree (mean Kendall tau between their rankings "
                f"{agreement[key]['mean_tau']:.2f}, below {SEEDS_AGREE}): do not trust its ranking"
            )
        taus = [t for t in against[key].values() if t is not None]
        if taus and max(taus) < 0:
            simple = ", ".join(f"{s} {t:.2f}" for s, t in against[key].items() if t is not None)
            warnings.append(
                f"{key}: ranks against every simple metric (Kendall tau with {simple}): check it before use"
            )
    if "motion" in ensembles:
        warnings += unlike_motion({k: e for k, e in ensembles.items() if k != "motion"}, ensembles["motion"])
    report = {**first, "trajectories": rows, "warnings": warnings, "ranking": dict(first["ranking"])}
    report["seeds"] = {"seeds": list(seeds), "agreement": agreement, "with_simple_metrics": against}
    keys = tuple(report["scores"])
    grouped = [
        {**r, "subject": f"level {r['skill']}" if first["grouped_by"] == "skill" else r["subject"]} for r in rows
    ]
    report["groups"] = subject_table(grouped, keys)
    labelled = [r for r in rows if isinstance(r.get("skill"), int | float)]
    if len({r["skill"] for r in labelled}) > 1:
        for key in learned:
            vals = [r[key + "_z"] if r[key + "_z"] is not None else float("nan") for r in labelled]
            result = rank_correlations(vals, [r["skill"] for r in labelled])
            report["ranking"][key] = {**result, "higher_is_better": True, "of": f"mean over {len(seeds)} seeds"}
    return report


def _finite(x) -> float | None:
    """A float, or None for NaN."""
    return None if x is None or not np.isfinite(x) else float(x)
