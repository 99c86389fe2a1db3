"""Score many files and gather the results: per trajectory, per group, and the ranking against labels."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Iterable
from pathlib import Path

from ..data.trajectory import TrajectoryError
from .agreement import unlike_motion
from .ranking import rank_correlations, subject_table
from .scoring import HIGHER_IS_BETTER, LEARNED, NORMALISED, SCORES, Scorer, TrajectoryScores

COLUMNS = SCORES
TOUR_COLUMNS = ("economy", "safety", "contacts")  # abdomen scenes only
SCORING_ERRORS = (TrajectoryError, ValueError, OSError)  # a file that raises one is reported, the rest scored


def trajectory_files(paths: Iterable[Path]) -> list[Path]:
    """The .npz files named, and those inside named folders (sorted); missing paths are kept to be reported."""
    files = []
    for p in map(Path, paths):
        files += sorted(p.glob("*.npz")) if p.is_dir() else [p]
    return files


def score_files(
    scorer: Scorer, files: list[Path], on_file: Callable[[Path], None] | None = None
) -> tuple[list[TrajectoryScores], list[str]]:
    """Score every file; a bad or foreign file becomes a message naming it, and the rest are still scored."""
    scored, problems = [], []
    for f in files:
        try:
            scored.append(scorer.score_file(f))
        except SCORING_ERRORS as e:
            problems.append(problem_text(f, e))
        if on_file is not None:
            on_file(f)
    return scored, problems


def problem_text(path: Path, error: Exception) -> str:
    """Why a file was not scored, naming it."""
    text = str(error)
    return text if str(path) in text else f"{path}: {text}"


def row(s: TrajectoryScores) -> dict:
    """One flat row: normalised learned and heuristic scores, raw kinematic ones, and the labels."""
    out = {
        "file": s.name,
        "subject": s.subject,
        "skill": s.skill,
        "source": s.meta.get("source"),
        "success": s.meta.get("success"),
    }
    for k in COLUMNS + tuple(k for k in TOUR_COLUMNS if k in s.scores):
        normalised = s.normalised.get(k)
        out[k] = normalised if k in NORMALISED and normalised is not None else s.scores.get(k)
        if k in NORMALISED:
            out[k + "_raw"] = s.scores.get(k)
    return out


def group_key(rows: list[dict]) -> str:
    """Group by subject where subjects repeat, else by skill label where there is one, else by subject."""
    subjects = [r["subject"] for r in rows]
    if len(set(subjects)) < len(subjects) or all(r["skill"] is None for r in rows):
        return "subject"
    return "skill"


def build_report(scored: list[TrajectoryScores], references: dict, problems: list[str], learned: bool) -> dict:
    """Everything a reader or a machine needs: references, rows, groups, rankings, problems."""
    rows = [row(s) for s in scored]
    keys = tuple(k for k in COLUMNS if k not in LEARNED or (learned and any(r[k] is not None for r in rows)))
    keys += tuple(k for k in TOUR_COLUMNS if rows and k in rows[0])
    by = group_key(rows) if rows else "subject"
    grouped = [{**r, "subject": f"level {r['skill']}" if by == "skill" else r["subject"]} for r in rows]
    warnings = [
        f"{k}: the random policy scores above the scripted expert ({references['random'][k]:.4g} vs "
        f"{references['expert'][k]:.4g}): it is shown raw, not normalised"
        for k in NORMALISED
        if k in keys and _inverted(references, k)
    ]
    if "motion" in keys:
        learned = {k: raw_column(rows, k) for k in ("reward", "value") if k in keys}
        warnings += unlike_motion(learned, raw_column(rows, "motion"))
    report = {
        "references": references,
        "warnings": warnings,
        "grouped_by": by,
        "scores": list(keys),
        "normalisation": "heuristic, reward, value: 0 = random policy, 1 = scripted expert; "
        "motion: summed log-likelihood of each step's motion under the recordings learned from; "
        "subtasks: fraction done; path_length m, time s, smoothness = log dimensionless jerk",
        "groups": subject_table(grouped, keys),
        "trajectories": rows,
        "problems": problems,
        "ranking": {},
    }
    labelled = [r for r in rows if isinstance(r["skill"], int | float)]
    if len({r["skill"] for r in labelled}) > 1:
        for k in keys:
            vals = raw_column(labelled, k)  # normalising by references may flip the order: rank raw
            sign = 1.0 if HIGHER_IS_BETTER[k] else -1.0  # rank so that "better" agrees with a higher label
            result = rank_correlations([sign * v for v in vals], [r["skill"] for r in labelled])
            result["level_means"] = {level: sign * m for level, m in result["level_means"].items()}
            report["ranking"][k] = {**result, "higher_is_better": HIGHER_IS_BETTER[k]}
    return report


def raw_column(rows: list[dict], key: str) -> list[float]:
    """Each row's score before normalisation (NaN where it has none)."""
    raw = key + "_raw" if key in NORMALISED else key
    return [math.nan if r[raw] is None else r[raw] for r in rows]


def _inverted(references: dict, key: str) -> bool:
    """True where the random reference is above the expert one."""
    lo, hi = references.get("random", {}).get(key), references.get("expert", {}).get(key)
    return lo is not None and hi is not None and hi < lo


def csv_text(report: dict) -> str:
    """The per-trajectory rows as CSV."""
    rows = report["trajectories"]
    buf = io.StringIO()
    if rows:
        writer = csv.DictWriter(buf, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return buf.getvalue()
