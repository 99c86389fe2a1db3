"""Ranking statistics: Spearman rho and Kendall tau-b against skill labels, with bootstrap intervals."""

from __future__ import annotations

import math
import warnings

import numpy as np

PAIR_LIMIT = 2000  # samples up to which n x n pair counts are cheap; beyond, scipy's own statistics
BOOT_PAIR_LIMIT = 300  # the bootstrap's pair counts cost n_boot x n^2: beyond, scipy per resample (same bits)
BOOT_ELEMENTS = 200_000  # resampled values held at once by the bootstrap (its memory does not grow with samples)


def _finite(x) -> float | None:
    """A float, or None where the statistic is undefined."""
    return None if x is None or not math.isfinite(float(x)) else float(x)


def _ranks(a: np.ndarray) -> np.ndarray:
    """Average ranks (1-based, ties share their mean rank) of each row, as scipy.stats.rankdata; exact."""
    order = np.argsort(a, axis=1, kind="mergesort")
    s = np.take_along_axis(a, order, axis=1)
    n = a.shape[1]
    idx = np.broadcast_to(np.arange(n), a.shape)
    starts = np.ones(a.shape, bool)
    starts[:, 1:] = s[:, 1:] != s[:, :-1]
    ends = np.ones(a.shape, bool)
    ends[:, :-1] = starts[:, 1:]
    first = np.maximum.accumulate(np.where(starts, idx, 0), axis=1)
    last = np.minimum.accumulate(np.where(ends, idx, n - 1)[:, ::-1], axis=1)[:, ::-1]
    ranks = np.empty(a.shape)
    np.put_along_axis(ranks, order, (first + last) / 2 + 1, axis=1)
    return ranks


def _spearman(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Spearman rho of each row pair (as scipy's spearmanr, NaN for a constant row), all rows at once.

    Ranks are half-integers and their mean is exactly (n + 1) / 2, so the sums below are exact in any order and
    the result is bit for bit scipy's (Pearson correlation of the ranks, as numpy's corrcoef divides it)."""
    rx, ry = _ranks(x), _ranks(y)
    dx, dy = rx - rx.mean(axis=1, keepdims=True), ry - ry.mean(axis=1, keepdims=True)
    f = np.true_divide(1, x.shape[1] - 1)
    cxy, sx, sy = (dx * dy).sum(axis=1) * f, np.sqrt((dx * dx).sum(axis=1) * f), np.sqrt((dy * dy).sum(axis=1) * f)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = np.clip(cxy / sy / sx, -1, 1)
    return np.where((x == x[:, :1]).all(axis=1) | (y == y[:, :1]).all(axis=1), np.nan, rho)


def _pair_counts(x: np.ndarray, y: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(concordant minus discordant pairs, pairs tied in x, pairs tied in y) of samples of (x, y) that hold each
    point `counts[b, i]` times: a sample's pairs are the original pairs weighted by the product of their counts."""
    sx, sy = np.sign(x[:, None] - x[None, :]).astype(np.int64), np.sign(y[:, None] - y[None, :]).astype(np.int64)
    n = counts.sum(axis=1)

    weights = counts.astype(float)  # BLAS: every sum below is an integer under 2**53, so exact in float64

    def pairs(m: np.ndarray) -> np.ndarray:
        """Sum of m over all ordered pairs (i, j) of each sample, i == j included."""
        return np.rint(((weights @ m) * weights).sum(axis=1)).astype(np.int64)

    con_minus_dis = pairs(sx * sy) // 2  # each unordered pair counted twice
    xtie, ytie = (pairs((sx == 0).astype(np.int64)) - n) // 2, (pairs((sy == 0).astype(np.int64)) - n) // 2
    return con_minus_dis, xtie, ytie


def _tau_b(con_minus_dis, xtie, ytie, tot: int):
    """Kendall tau-b from pair counts as scipy divides it, clipped to [-1, 1]; NaN where x or y is constant."""
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = con_minus_dis / np.sqrt(tot - xtie) / np.sqrt(tot - ytie)
    return np.where((xtie == tot) | (ytie == tot), np.nan, np.minimum(1.0, np.maximum(-1.0, tau)))


def _boot_kendall(x: np.ndarray, y: np.ndarray, draws: np.ndarray) -> np.ndarray:
    """Kendall tau-b of (x, y) resampled at each row of `draws` (as scipy's kendalltau, NaN for a constant
    resample), from exact integer pair counts."""
    (rows, k), n = draws.shape, len(x)
    counts = np.bincount((draws + n * np.arange(rows)[:, None]).ravel(), minlength=rows * n).reshape(rows, n)
    return _tau_b(*_pair_counts(x, y, counts), k * (k - 1) // 2)


def _tie_sums(v: np.ndarray) -> tuple[int, int, int]:
    """Tied pairs and the two tie terms of the variance of tau, as scipy's kendalltau counts them."""
    cnt = np.unique(v, return_counts=True)[1].astype(np.int64)
    cnt = cnt[cnt > 1]
    return (
        int((cnt * (cnt - 1) // 2).sum()),
        int((cnt * (cnt - 1.0) * (cnt - 2)).sum()),
        int((cnt * (cnt - 1.0) * (2 * cnt + 5)).sum()),
    )


def _scipy_stats(scores: np.ndarray, labels: np.ndarray) -> tuple[float, float, float, float]:
    """scipy's own (rho, p, tau-b, p): for the exact Kendall p-value and for samples too large for pair counts."""
    from scipy.stats import kendalltau, spearmanr  # 0.4 s to import: only where the fast path does not apply

    with warnings.catch_warnings():  # constant input: scipy warns and returns NaN, which we report as None
        warnings.simplefilter("ignore")
        rho = spearmanr(scores, labels)
        tau = kendalltau(scores, labels, variant="b")
    return rho.statistic, rho.pvalue, tau.statistic, tau.pvalue


def _stats(scores: np.ndarray, labels: np.ndarray) -> tuple[float, float, float, float]:
    """(rho, p, tau-b, p) bit for bit as scipy's spearmanr and kendalltau(variant="b"), NaN where undefined."""
    n = len(scores)
    if n < 2 or n > PAIR_LIMIT:
        return _scipy_stats(scores, labels)
    tot = n * (n - 1) // 2
    cmd, xtie, ytie = (int(v[0]) for v in _pair_counts(scores, labels, np.ones((1, n), np.int64)))
    if xtie == 0 and ytie == 0 and (n <= 33 or min(tot - cmd, tot + cmd) <= 2):  # scipy's exact p-value
        return _scipy_stats(scores, labels)
    from scipy.special import ndtr, stdtr  # here: 0.17 s to import, which `fastrl score` spends while drawing

    rho = _spearman(scores[None], labels[None])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = rho * np.sqrt(((n - 2) / ((rho + 1.0) * (1.0 - rho))).clip(0))
    rho_p = 2 * stdtr(n - 2, -np.abs(t))
    tau = _tau_b(cmd, xtie, ytie, tot)
    if np.isnan(tau):
        return float(rho[0]), float(rho_p[0]), np.nan, np.nan
    (_, x0, x1), (_, y0, y1) = _tie_sums(scores), _tie_sums(labels)
    m = n * (n - 1.0)
    var = (m * (2 * n + 5) - x1 - y1) / 18 + (2 * xtie * ytie) / m + x0 * y0 / (9 * m * (n - 2))
    tau_p = 2 * ndtr(-np.abs(cmd / np.sqrt(var)))
    return float(rho[0]), float(rho_p[0]), float(tau), float(tau_p)


def _tau_of(x: np.ndarray, y: np.ndarray) -> float:
    """Kendall tau-b alone (no p-value), as scipy's."""
    n = len(x)
    return float(_tau_b(*(int(v[0]) for v in _pair_counts(x, y, np.ones((1, n), np.int64))), n * (n - 1) // 2))


def _bootstrap(scores: np.ndarray, labels: np.ndarray, n_boot: int, rng) -> np.ndarray:
    """(Spearman rho, Kendall tau-b) of `n_boot` resamples, a few at a time so that memory stays bounded however
    many samples there are (each resample's figures do not depend on how many are computed at once); beyond
    BOOT_PAIR_LIMIT samples, Kendall's by scipy one resample at a time (the same bits, cheaper than n^2 pairs)."""
    n = len(scores)
    rows = max(1, min(n_boot, BOOT_ELEMENTS // max(1, n)))
    out = [np.empty((0, 2))]
    for start in range(0, n_boot, rows):
        i = rng.integers(0, n, (min(rows, n_boot - start), n))  # the same draws as one resample at a time
        if n <= BOOT_PAIR_LIMIT:
            tau = _boot_kendall(scores, labels, i)
        else:
            tau = np.array([_kendall_scipy(scores[d], labels[d]) for d in i])
        out.append(np.stack([_spearman(scores[i], labels[i]), tau], axis=1))
    return np.concatenate(out)


def _kendall_scipy(x: np.ndarray, y: np.ndarray) -> float:
    """scipy's Kendall tau-b alone (NaN where undefined)."""
    from scipy.stats import kendalltau

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return float(kendalltau(x, y, variant="b").statistic)


def rank_correlations(scores, labels, n_boot: int = 1000, seed: int = 0, level: float = 0.95) -> dict:
    """Spearman and Kendall tau-b of scores against labels, bootstrap CIs, and the order of level means."""
    scores, labels = np.asarray(scores, float), np.asarray(labels, float)
    keep = np.isfinite(scores) & np.isfinite(labels)
    scores, labels = scores[keep], labels[keep]
    rho, rho_p, tau, tau_p = _stats(scores, labels)
    boot = _bootstrap(scores, labels, n_boot if len(scores) > 2 else 0, np.random.default_rng(seed))
    lo, hi = (1 - level) / 2 * 100, (1 + level) / 2 * 100

    def ci(col: int) -> list | None:
        vals = boot[:, col][np.isfinite(boot[:, col])]
        return None if len(vals) < 10 else [float(np.percentile(vals, lo)), float(np.percentile(vals, hi))]

    levels = np.unique(labels)
    means = [float(scores[labels == v].mean()) for v in levels]
    level_tau = _tau_of(np.array(means), levels) if len(levels) > 1 else float("nan")
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
