"""The laparoscopic study in Rerun and as a PNG: anatomy, paths coloured by learned value, Table 3 plots."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from ..model.compiler import CompiledTask
from .assessment import _colours, log_coloured_path
from .scene import log_scene
from .stream import saved_stream

PANELS = (("reward", "economy"), ("reward", "safety"), ("value", "economy"), ("value", "safety"))


def table3_markdown(result: dict) -> str:
    """Table 3 as markdown: Spearman's rho (p-value) of learned reward and value against economy and safety."""
    lines = [
        "## Learned scores against economy and safety (Spearman's rho, p-value)",
        "",
        "| model | reward-economy | reward-safety | value-economy | value-safety |",
        "|---|---|---|---|---|",
    ]
    for algo, cells in result["table3"].items():
        if algo == "heuristic":
            continue
        lines.append(f"| {algo.upper()} | " + " | ".join(_cell(cells[f"{k}-{m}"]) for k, m in PANELS) + " |")
    h = result["table3"]["heuristic"]
    lines += [
        "",
        f"Heuristic return: economy {_cell(h['heuristic-economy'])}, safety {_cell(h['heuristic-safety'])}.",
        "",
        f"{result['n']} procedures; the inverse-RL demonstrations are the {len(result['best'])} best by "
        "the heuristic return.",
        "",
        *(f"- {k}: {v}" for k, v in result["metrics"].items()),
    ]
    return "\n".join(lines)


def _cell(c: dict) -> str:
    """'rho (p)' or '-'."""
    return "-" if c["rho"] is None else f"{c['rho']:.2f} ({c['p']:.2g})"


def _unit(x: np.ndarray) -> np.ndarray:
    """Scale to 0..100 (constant: 50)."""
    span = np.ptp(x)
    return np.full(len(x), 50.0) if span == 0 else 100.0 * (x - x.min()) / span


def plot_correlations(result: dict, path: Path) -> Path:
    """Fig. 8 (right): each learned score against economy and safety, one dot per procedure by skill level."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    algos = [a for a in result["table3"] if a != "heuristic"]
    rows = result["procedures"]
    skill = np.array([r["skill"] or 0 for r in rows], float)
    fig, axes = plt.subplots(len(algos), 4, figsize=(14, 3.6 * len(algos)), squeeze=False, layout="constrained")
    for i, algo in enumerate(algos):
        for j, (k, m) in enumerate(PANELS):
            ax = axes[i, j]
            sc = ax.scatter([r[m] for r in rows], [r[f"{algo}_{k}"] for r in rows], c=skill, cmap="viridis", s=14)
            c = result["table3"][algo][f"{k}-{m}"]
            ax.set_title(f"{algo.upper()} {k} vs {m}\nrho {_cell(c)}", fontsize=9)
            ax.set_xlabel(f"{m} (m)", fontsize=8)
            ax.set_ylabel(f"learned {k}", fontsize=8)
            ax.tick_params(labelsize=7)
    fig.colorbar(sc, ax=axes.ravel().tolist(), label="skill level", shrink=0.8)
    fig.suptitle(f"{result['spec']}: learned scores of {result['n']} procedures against the ground-truth metrics")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def log_study(
    path: Path, recording_id: str, task: CompiledTask, scored, learned: dict, result: dict, figure: Path | None = None
) -> Path:
    """Write the study's .rrd: anatomy, every camera path coloured by learned value, Table 3 plots."""
    rec = saved_stream(path, recording_id)
    try:
        log_scene(rec, task, root="world")
        algo = "airl" if "airl" in learned else next(iter(learned), None)
        values = [s.values for s in learned[algo]] if algo else [s.time for s in scored]
        lo, hi = np.percentile(np.concatenate(values), [5, 95])
        for s, v in zip(scored, values):
            log_coloured_path(rec, f"world/procedures/level_{s.skill}/{s.name}", s.tip, _colours(v, lo, hi))
        rows = result["procedures"]
        skill = np.array([r["skill"] or 0 for r in rows], float)
        colours = _colours(skill, skill.min(), skill.max())
        labels = [f"{r['name']}: {r.get('economy', 0):.3f} m" for r in rows]
        views = []
        for a in (a for a in result["table3"] if a != "heuristic"):
            for k, m in PANELS:
                x, y = _unit(np.array([r[m] for r in rows])), _unit(np.array([r[f"{a}_{k}"] for r in rows]))
                entity = f"correlations/{a}/{k}_{m}"
                rec.log(
                    entity, rr.Points2D(np.column_stack([x, -y]), colors=colours, radii=1.2, labels=labels), static=True
                )
                c = result["table3"][a][f"{k}-{m}"]
                views.append(rrb.Spatial2DView(origin=f"/{entity}", name=f"{a.upper()} {k} vs {m}: rho {_cell(c)}"))
        rec.log("summary", rr.TextDocument(table3_markdown(result), media_type=rr.MediaType.MARKDOWN), static=True)
        tabs = [rrb.Grid(*views, name="interactive: score (up) vs metric (right), 0-100 scaled")]
        if figure is not None and Path(figure).is_file():
            rec.log("figure", rr.EncodedImage(path=figure), static=True)
            tabs.insert(0, rrb.Spatial2DView(origin="/figure", name="correlations (Fig. 8)"))
        rec.send_blueprint(
            rrb.Blueprint(
                rrb.Horizontal(
                    rrb.Vertical(
                        rrb.Spatial3DView(origin="/world", name=f"camera paths by learned value ({algo})"),
                        rrb.TextDocumentView(origin="/summary", name="Table 3"),
                        row_shares=[3, 2],
                    ),
                    rrb.Tabs(*tabs, active_tab=0),
                    column_shares=[2, 3],
                ),
                collapse_panels=True,
            )
        )
    finally:
        rec.flush()
        rec.disconnect()
    return Path(path)
