"""Ranking statistics: Spearman rho and Kendall tau-b against skill labels, with bootstrap intervals."""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.stats import kendalltau, spearmanr


def _finite(x) -> float | None:
    """A float, or None where the statistic is undefined."""
    return None if x is None or not math.isfinite(float(x)) else float(x)


def _stats(scores: np.ndarray, labels: np.ndarray) -> tuple[float, float, float, float]:
    """(rho, p, tau-b, p), NaN where undefined (constant input)."""
    with warnings.catch_warnings():  # constant input: scipy warns and returns NaN, which we report as None
        warnings.simplefilter("ignore")
        rho = spearmanr(scores, labels)
        tau = kendalltau(scores, labels, variant="b")
    return rho.statistic, rho.pvalue, tau.statistic, tau.pvalue


def rank_correlations(scores, labels, n_boot: int = 1000, seed: int = 0, level: float = 0.95) -> dict:
    """Spearman and Kendall tau-b of scores against labels, bootstrap CIs, and the order of level means."""
    scores, labels = np.asarray(scores, float), np.asarray(labels, float)
    keep = np.isfinite(scores) & np.isfinite(labels)
    scores, labels = scores[keep], labels[keep]
    rho, rho_p, tau, tau_p = _stats(scores, labels)
    rng = np.random.default_rng(seed)
    boot = []
    for _ in range(n_boot if len(scores) > 2 else 0):
        i = rng.integers(0, len(scores), len(scores))
        boot.append(_stats(scores[i], labels[i])[::2])
    boot = np.array(boot, float).reshape(-1, 2)
    lo, hi = (1 - level) / 2 * 100, (1 + level) / 2 * 100

    def ci(col: int) -> list | None:
        vals = boot[:, col][np.isfinite(boot[:, col])]
        return None if len(vals) < 10 else [float(np.percentile(vals, lo)), float(np.percentile(vals, hi))]

    levels = np.unique(labels)
    means = [float(scores[labels == v].mean()) for v in levels]
    level_tau = _stats(np.array(means), levels)[2] if len(levels) > 1 else float("nan")
    return {
        "n": int(len(scores)),
        "spearman": _finite(rho),
        "spearman_p": _finite(rho_p),
        "spearman_ci": ci(0),
        "kendall_tau_b": _finite(tau),
        "kendall_p": _finite(tau_p),
        "kendall_ci": ci(1),
        "level_means": dict(zip([_label(v) for v in levels], means)),
        "levels_in_order": bool(len(levels) > 1 and np.all(np.diff(means) > 0)),
        "kendall_tau_b_of_level_means": _finite(level_tau),
    }


def _label(v: float):
    """A label as it was written: integers stay integers."""
    return int(v) if float(v).is_integer() else float(v)


def subject_table(rows: list[dict], keys: tuple[str, ...]) -> list[dict]:
    """Per subject: trajectory count, skill label, and mean and standard deviation of each key."""
    by: dict[str, list[dict]] = {}
    for r in rows:
        by.setdefault(r["subject"], []).append(r)
    out = []
    for subject, rs in by.items():
        entry = {"subject": subject, "n": len(rs), "skill": rs[0].get("skill")}
        for k in keys:
            vals = np.array([r[k] for r in rs if r.get(k) is not None], float)
            entry[k] = None if len(vals) == 0 else float(vals.mean())
            entry[k + "_sd"] = None if len(vals) == 0 else float(vals.std())
        out.append(entry)
    return sorted(out, key=lambda e: (-(e[keys[0]] if e[keys[0]] is not None else -math.inf), e["subject"]))
