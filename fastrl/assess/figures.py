"""Assessment pictures as PNG: paths coloured by learned value (Fig. 6), deviation from the expert (Fig. 7),
score distributions per group."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .kinematic import deviation_by_progress
from .scoring import TrajectoryScores

MAX_PANELS = 6
PANEL_WIDTH = 2.9  # inches of one panel of the paths figure


def group_of(s: TrajectoryScores, by: str) -> str:
    """The group label a trajectory is drawn under."""
    return f"level {s.skill}" if by == "skill" else s.subject


def _groups(scored: list[TrajectoryScores], by: str) -> dict[str, list[TrajectoryScores]]:
    """Trajectories by group, best-labelled first (highest skill, else by name)."""
    groups: dict[str, list[TrajectoryScores]] = {}
    for s in scored:
        groups.setdefault(group_of(s, by), []).append(s)
    return dict(sorted(groups.items(), key=lambda kv: (-(kv[1][0].skill or 0), kv[0])))


def deviations(scored: list[TrajectoryScores], reference: dict) -> dict[str, np.ndarray]:
    """Per trajectory: distance (mm) to the expert's path on the same seed, at each percent of the procedure."""
    out = {}
    for s in scored:
        ref = reference.get(s.seed)
        if ref is not None:
            out[s.name] = 1000.0 * deviation_by_progress(s.tip, s.time, ref[1], ref[0])
    return out


def plot_paths(scored: list[TrajectoryScores], by: str, path: Path, radius: float) -> Path:
    """Fig. 6: tip paths projected on the dome's XY plane, coloured by learned value (or by time)."""
    plt = _pyplot()
    from matplotlib.collections import LineCollection

    groups = list(_groups(scored, by).items())[:MAX_PANELS]
    xy_all = np.concatenate([s.tip[:, :2] for s in scored]) * 1000
    (x0, y0), (x1, y1) = xy_all.min(axis=0) - 10, xy_all.max(axis=0) + 10
    # laid out in inches here (each panel as tall as its data, with equal axes), not by a tight bounding box: that
    # would draw the 40k dots twice
    n, w = len(groups), PANEL_WIDTH
    h = float(np.clip(w * (y1 - y0) / (x1 - x0), 0.8, 2 * w))
    left, gap, right, bottom, top = 0.75, 0.2, 1.25, 0.55, 0.75
    fig = plt.figure(figsize=(max(left + n * w + (n - 1) * gap + right, 6.0), bottom + h + top))  # the title fits
    axes = [_axes(fig, left + i * (w + gap), bottom, w, h) for i in range(n)]
    with_values = [s.values for s in scored if s.values is not None]
    lo, hi = np.percentile(np.concatenate(with_values), [5, 95]) if with_values else (0.0, 1.0)
    sc = None
    for ax, (name, members) in zip(axes, groups):  # one artist per kind and panel, not per trajectory
        ax.add_patch(plt.Circle((0, 0), radius * 1000, fill=False, color="0.6", lw=1))
        xys = [s.tip[:, :2] * 1000 for s in members]
        ax.add_collection(LineCollection(xys, colors="0.8", linewidths=0.5, zorder=1))
        learned = members[0].values is not None
        colour = np.concatenate([s.values if learned else s.time for s in members])
        points = np.concatenate(xys)
        sc = ax.scatter(  # dots without an outline (stroking 40k outlines doubled the drawing), as large as before
            points[:, 0],
            points[:, 1],
            c=colour,
            s=10,
            linewidths=0,
            cmap="viridis",
            vmin=lo if learned else None,
            vmax=hi if learned else None,
            zorder=2,
        )
        ax.scatter(*np.array([xy[0] for xy in xys]).T, marker="*", s=60, color="k", zorder=3)
        ax.scatter(*np.array([xy[-1] for xy in xys]).T, marker="*", s=60, color="tab:red", zorder=3)
        ax.set(title=f"{name} (n={len(members)})", xlabel="x (mm)", aspect="equal", xlim=(x0, x1), ylim=(y0, y1))
        if ax is not axes[0]:
            ax.tick_params(labelleft=False)
    axes[0].set_ylabel("y (mm)")
    if sc is not None:
        cax = _axes(fig, left + n * w + (n - 1) * gap + 0.25, bottom, 0.12, h)
        fig.colorbar(sc, cax=cax, label="learned value V(s)" if with_values else "time (s)")
    fig.suptitle(
        "Camera paths projected on the dome's XY plane (black star: start, red star: end)",
        fontsize=10,
        y=1 - 0.12 / (bottom + h + top),
    )
    return _save(fig, path)


def plot_deviation(scored: list[TrajectoryScores], devs: dict[str, np.ndarray], by: str, path: Path) -> Path:
    """Fig. 7: deviation from the expert's path over the percentage of the procedure, mean and band per group."""
    plt = _pyplot()

    fig = plt.figure(figsize=(6.4, 3.8))
    ax = _axes(fig, 0.75, 0.6, 5.45, 2.85)
    for name, members in _groups(scored, by).items():
        rows = np.array([devs[s.name] for s in members if s.name in devs])
        if len(rows) == 0:
            continue
        pct = np.linspace(0, 100, rows.shape[1])
        mean = rows.mean(axis=0)
        line = ax.plot(pct, mean, label=f"{name} ({rows.mean():.0f} mm)")[0]
        ax.fill_between(
            pct, np.percentile(rows, 25, axis=0), np.percentile(rows, 75, axis=0), color=line.get_color(), alpha=0.15
        )
    ax.set(
        xlabel="procedure completed (% of the attempt's duration)",
        ylabel="distance to expert path (mm)",
    )
    ax.set_title("Deviation from the scripted expert on the same seed (mean, IQR)", fontsize=10)
    ax.legend(fontsize=8)
    return _save(fig, path)


def plot_distributions(report: dict, path: Path) -> Path:
    """Each score's distribution per group (strip and box plots)."""
    plt = _pyplot()

    keys = report["scores"]
    rows = report["trajectories"]
    by = report["grouped_by"]
    label = (lambda r: f"L{r['skill']}") if by == "skill" else (lambda r: r["subject"])
    names = [g["subject"] for g in report["groups"]]
    names = [n.replace("level ", "L") for n in names] if by == "skill" else names
    fig = plt.figure(figsize=(2.6 * len(keys), 3.4))
    axes = [_axes(fig, 0.55 + 2.6 * i, 0.5, 1.95, 2.4) for i in range(len(keys))]  # tick labels fit in the gaps
    for ax, k in zip(axes, keys):
        data = [[r[k] for r in rows if label(r) == n and r[k] is not None] for n in names]
        _boxes(ax, data)
        x = [np.full(len(d), i) + np.linspace(-0.15, 0.15, len(d)) for i, d in enumerate(data, start=1)]
        cycle = [f"C{i % 10}" for i, d in enumerate(data) for _ in d]  # each group its colour, in one artist
        ax.scatter(np.concatenate(x), np.concatenate([np.asarray(d, float) for d in data]), s=6, alpha=0.6, c=cycle)
        ax.set_xticks(range(1, len(names) + 1), names, rotation=45, fontsize=7)
        rank = report["ranking"].get(k)
        ax.set_title(
            k + (f"\ntau-b {rank['kendall_tau_b']:.2f}" if rank and rank["kendall_tau_b"] is not None else ""),
            fontsize=9,
        )
    return _save(fig, path)


def _boxes(ax, data: list[list[float]]) -> None:
    """Box plots at x = 1, 2, ... as matplotlib's boxplot draws them without fliers (quartiles, median, whiskers to
    the last point within 1.5 IQR), in two artists instead of six per box."""
    from matplotlib import cbook
    from matplotlib.collections import LineCollection

    black, medians = [], []
    for x, stats in enumerate(cbook.boxplot_stats([np.asarray(d, float) for d in data]), start=1):
        if not np.isfinite(stats["med"]):  # an empty group
            continue
        q1, q3, lo, hi, a, b = stats["q1"], stats["q3"], stats["whislo"], stats["whishi"], x - 0.25, x + 0.25
        black += [[(a, q1), (b, q1), (b, q3), (a, q3), (a, q1)], [(x, q1), (x, lo)], [(x, q3), (x, hi)]]
        black += [[(x - 0.125, lo), (x + 0.125, lo)], [(x - 0.125, hi), (x + 0.125, hi)]]
        medians.append([(a, stats["med"]), (b, stats["med"])])
    ax.add_collection(LineCollection(black, colors="k", linewidths=1.0, zorder=2))
    ax.add_collection(LineCollection(medians, colors="C1", linewidths=1.0, zorder=2))
    ax.set_xlim(0.5, len(data) + 0.5)


def draw_path_figures(scored: list[TrajectoryScores], devs: dict, by: str, paths: dict, radius: float) -> dict:
    """The paths-by-value and deviation PNGs (they need no report), each drawn once; their paths by kind."""
    return {
        "paths": plot_paths(scored, by, paths["paths"], radius),
        "deviation": plot_deviation(scored, devs, by, paths["deviation"]),
    }


def _pyplot():
    """matplotlib.pyplot on the file-only Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _axes(fig, left: float, bottom: float, width: float, height: float):
    """Axes at a place given in inches from the figure's lower left corner (figures here are laid out by hand: a
    layout engine or a tight bounding box lays out, or draws, a figure twice)."""
    fw, fh = fig.get_size_inches()
    return fig.add_axes((left / fw, bottom / fh, width / fw, height / fh))


def _save(fig, path: Path) -> Path:
    """Write and close a figure."""
    plt = _pyplot()

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, pil_kwargs={"compress_level": 3})  # a third faster than 6, files 10% larger
    plt.close(fig)
    return path
