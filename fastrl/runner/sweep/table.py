"""A sweep's results: mean and sd over seeds per configuration, the best one, written as JSON, CSV and a figure."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from ..runs.runfiles import read_eval
from .plan import is_finished, read_manifest

METRICS = {"success": "success_rate", "subtasks": "subtasks_completed", "return": "return_mean"}
COLUMNS = (*METRICS, "wall_s")


def trial_row(run: Path) -> dict | None:
    """A finished trial's figures (evaluation of its agent, wall time, node), or None if it did not finish."""
    if not is_finished(run):
        return None
    agent = read_eval(run)["agent"]
    info = json.loads((run / "trial.json").read_text()) if (run / "trial.json").exists() else {}
    row = {k: float(agent[v]) for k, v in METRICS.items()}
    return row | {"wall_s": info.get("wall_s"), "node_id": info.get("node_id")}


def _stats(values: list[float]) -> tuple[float | None, float | None]:
    """Mean and sample sd (0 for one value); None for no values."""
    vals = np.array([v for v in values if v is not None], float)
    if vals.size == 0:
        return None, None
    return float(vals.mean()), float(vals.std(ddof=1)) if vals.size > 1 else 0.0


def summarize(sweep: Path, failed: list[dict] | None = None) -> dict:
    """Per configuration, mean and sd over its finished seeds; the best configuration by success, subtasks, return."""
    sweep = Path(sweep)
    manifest = read_manifest(sweep)
    trials = {t["name"]: t | {"result": trial_row(sweep / t["name"])} for t in manifest["trials"]}
    rows = []
    for c in manifest["configs"]:
        mine = [t for t in trials.values() if t["config"] == c["index"]]
        results = [t["result"] for t in mine if t["result"] is not None]
        row = {"config": c["name"], "setting": c["setting"], "seeds": len(results), "of": len(mine)}
        for col in COLUMNS:
            row[f"{col}_mean"], row[f"{col}_sd"] = _stats([r[col] for r in results])
        rows.append(row)
    ranked = [r for r in rows if r["seeds"]]
    best = max(ranked, key=lambda r: (r["success_mean"], r["subtasks_mean"], r["return_mean"]), default=None)
    return {
        "spec": manifest["spec_name"],
        "grid": manifest["grid"],
        "seeds": manifest["seeds"],
        "rows": rows,
        "best": None if best is None else {"config": best["config"], "setting": best["setting"]},
        "trials": [
            {"trial": name, "seed": t["seed"], "config": t["config"], **(t["result"] or {"finished": False})}
            for name, t in trials.items()
        ],
        "failed": failed or [],
    }


def write_csv(summary: dict, path: Path) -> None:
    """One line per configuration: its setting, seeds, and each figure's mean and sd."""
    keys = list(summary["grid"])
    header = ["config", *keys, "seeds", *[f"{c}_{s}" for c in COLUMNS for s in ("mean", "sd")]]
    with Path(path).open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in summary["rows"]:
            figures = [r[f"{c}_{s}"] for c in COLUMNS for s in ("mean", "sd")]
            w.writerow([r["config"], *[r["setting"][k] for k in keys], r["seeds"], *figures])


def plot_sweep(summary: dict, path: Path) -> None:
    """Bars of mean +- sd per configuration for success, subtasks and return, with each seed as a dot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = summary["rows"]
    labels = [r["config"] for r in rows]
    fig, axes = plt.subplots(1, 3, figsize=(4 + 1.2 * len(rows) * 3, 4), squeeze=False)
    x = np.arange(len(rows))
    for ax, col in zip(axes[0], METRICS):
        means = [r[f"{col}_mean"] if r[f"{col}_mean"] is not None else np.nan for r in rows]
        sds = [r[f"{col}_sd"] or 0.0 for r in rows]
        ax.bar(x, means, yerr=sds, capsize=4, color="#7aa6c2")
        for t in summary["trials"]:
            if t.get(col) is not None:
                ax.plot(t["config"], t[col], "k.", ms=5)
        ax.set_xticks(x, labels, rotation=30, ha="right", fontsize=8)
        ax.set_title(col)
        if col != "return":
            ax.set_ylim(0, 1.05)
    fig.suptitle(f"sweep of {summary['spec']}: mean +- sd over seeds {summary['seeds']}")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_results(sweep: Path, failed: list[dict] | None = None) -> dict:
    """Summarize a sweep and write results.json, results.csv and results.png into its folder."""
    sweep = Path(sweep)
    summary = summarize(sweep, failed)
    (sweep / "results.json").write_text(json.dumps(summary, indent=2))
    write_csv(summary, sweep / "results.csv")
    plot_sweep(summary, sweep / "results.png")
    return summary
