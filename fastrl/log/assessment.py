"""An assessment in Rerun: scored paths in 3D and on the XY plane coloured by value, deviation curves, tables."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from matplotlib import colormaps  # not pyplot: the colour map alone

from ..model.compiler import CompiledTask
from .scene import log_scene
from .stream import saved_stream


def skip_pandas_probe() -> None:
    """Make pyarrow skip its pandas probe in this process. Rerun converts every logged array with pyarrow, which
    imports pandas (0.4-0.8 s) on its first conversion only to ask whether the input is a pandas object; Rerun never
    passes one. pyarrow remembers the failed import for that question only: anything that needs pandas through
    pyarrow (to_pandas, from_pandas) still imports it then. Nothing changes where pandas is already imported."""
    if "pandas" in sys.modules:
        return
    import pyarrow as pa

    sys.meta_path.insert(0, _NoPandas())
    try:
        pa.array([0])
    finally:
        sys.meta_path[:] = [f for f in sys.meta_path if not isinstance(f, _NoPandas)]


class _NoPandas:
    """A meta path finder under which importing pandas fails."""

    def find_spec(self, name, path=None, target=None):
        """Refuse pandas, pass on everything else."""
        if name.partition(".")[0] == "pandas":
            raise ImportError("pandas is hidden from pyarrow's probe")
        return None


def _colours(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """viridis-like RGB (uint8) of values scaled from [lo, hi]."""
    t = np.clip((values - lo) / max(hi - lo, 1e-12), 0.0, 1.0)
    return (colormaps["viridis"](t)[:, :3] * 255).astype(np.uint8)


def log_coloured_path(rec: rr.RecordingStream, entity: str, tip: np.ndarray, colours: np.ndarray) -> None:
    """A tip path as points in their colours (a score along it) over a thin grey line."""
    rec.log(entity, rr.Points3D(tip, colors=colours, radii=0.0008), static=True)
    rec.log(f"{entity}/path", rr.LineStrips3D([tip], colors=[[200, 200, 200]], radii=0.0002), static=True)


def _slug(text: str) -> str:
    """An entity-path-safe name."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", str(text)).strip("_") or "x"


def markdown_table(report: dict) -> str:
    """The group table and the ranking as markdown."""
    keys = report["scores"]
    lines = [
        f"## Scores by {report['grouped_by']}",
        "",
        "| group | n | " + " | ".join(keys) + " |",
        "|---|---|" + "---|" * len(keys),
    ]
    for g in report["groups"]:
        cells = [("-" if g[k] is None else f"{g[k]:.3g} ± {g[k + '_sd']:.2g}") for k in keys]
        lines.append(f"| {g['subject']} | {g['n']} | " + " | ".join(cells) + " |")
    if report["ranking"]:
        lines += [
            "",
            "## Ranking against skill labels",
            "",
            "| score | Spearman rho [95% CI] | Kendall tau-b [95% CI] | levels in order |",
            "|---|---|---|---|",
        ]
        for k, r in report["ranking"].items():

            def fmt(v, ci):
                return "-" if v is None else f"{v:.2f}" + (f" [{ci[0]:.2f}, {ci[1]:.2f}]" if ci else "")

            lines.append(
                f"| {k} | {fmt(r['spearman'], r['spearman_ci'])} | {fmt(r['kendall_tau_b'], r['kendall_ci'])}"
                f" | {'yes' if r['levels_in_order'] else 'no'} |"
            )
    if "seeds" in report:
        lines += ["", f"## Agreement over seeds {', '.join(map(str, report['seeds']['seeds']))}", ""]
        lines += [
            "| learned score | seeds' mean (min) Kendall tau | "
            + " | ".join(f"tau with {s}" for s in next(iter(report["seeds"]["with_simple_metrics"].values()), {}))
            + " |"
        ]
        lines += ["|---|---|" + "---|" * len(next(iter(report["seeds"]["with_simple_metrics"].values()), {}))]
        for k, a in report["seeds"]["agreement"].items():
            simple = report["seeds"]["with_simple_metrics"][k]
            tau = "-" if a["mean_tau"] is None else f"{a['mean_tau']:.2f} ({a['min_tau']:.2f})"
            lines.append(
                f"| {k} | {tau} | " + " | ".join("-" if v is None else f"{v:.2f}" for v in simple.values()) + " |"
            )
    lines += ["", report["normalisation"]] + [f"\n_Note: {w}_" for w in report.get("warnings", [])]
    if report["problems"]:
        lines += ["", "## Files not scored", ""] + [f"- {p}" for p in report["problems"]]
    return "\n".join(lines)


def log_assessment(
    path: Path, recording_id: str, task: CompiledTask, scored, report: dict, deviations: dict[str, np.ndarray], group_of
) -> Path:
    """Write an .rrd (same recording id as the run, so the viewer shows it with the run) and return its path."""
    skip_pandas_probe()
    rec = saved_stream(path, recording_id)
    try:
        log_scene(rec, task, root="world")
        values = [s.values for s in scored if s.values is not None]
        lo, hi = np.percentile(np.concatenate(values), [5, 95]) if values else (0.0, 1.0)
        for s in scored:
            base = f"{_slug(group_of(s))}/{_slug(s.name)}"
            v = s.values if s.values is not None else s.time
            colours = _colours(v, lo, hi) if s.values is not None else _colours(v, v.min(), v.max())
            log_coloured_path(rec, f"world/assessment/{base}", s.tip, colours)
            rec.log(
                f"assessment/xy/{base}",
                rr.Points2D(s.tip[:, :2] * [1000, -1000], colors=colours, radii=0.4),
                static=True,
            )
            if s.name in deviations:
                d = deviations[s.name]
                rec.log(f"assessment/deviation/{base}", rr.SeriesLines(names=s.name, widths=1.0), static=True)
                rec.send_columns(
                    f"assessment/deviation/{base}",
                    indexes=[rr.TimeColumn("percent", sequence=np.arange(len(d)))],
                    columns=rr.Scalars.columns(scalars=d),
                )
        videos = [v for v in (_log_video(rec, s, f"videos/{_slug(s.name)}") for s in scored) if v]
        _log_summary(rec, report)
        rec.send_blueprint(_blueprint(report, videos[:1]))
    finally:
        rec.flush()
        rec.disconnect()
    return Path(path)


def log_summary(path: Path, recording_id: str, report: dict) -> Path:
    """An .rrd of the group means and the summary table alone (scores over several seeds: no one set of paths)."""
    skip_pandas_probe()
    rec = saved_stream(path, recording_id)
    try:
        _log_summary(rec, report)
        bars = [rrb.BarChartView(origin=f"/assessment/scores/{k}", name=k) for k in report["scores"]]
        rec.send_blueprint(
            rrb.Blueprint(
                rrb.Horizontal(
                    rrb.TextDocumentView(origin="/assessment/summary", name="scores"),
                    rrb.Tabs(*bars, name="group means"),
                ),
                collapse_panels=True,
            )
        )
    finally:
        rec.flush()
        rec.disconnect()
    return Path(path)


def _log_summary(rec: rr.RecordingStream, report: dict) -> None:
    """Each score's group means as a bar chart, and the markdown table."""
    for k in report["scores"]:
        means = [g[k] if g[k] is not None else np.nan for g in report["groups"]]
        rec.log(f"assessment/scores/{k}", rr.BarChart(np.nan_to_num(np.array(means, float))), static=True)
    rec.log(
        "assessment/summary", rr.TextDocument(markdown_table(report), media_type=rr.MediaType.MARKDOWN), static=True
    )


def _log_video(rec: rr.RecordingStream, s, entity: str) -> str | None:
    """A trajectory read from a video: the video as an asset, its learned reward and value per frame beside it on
    the `video_time` timeline; the entity, or None for a trajectory without a video file."""
    from .video import log_video  # here: log.video imports from this module

    source = Path(str(s.meta.get("imported_from", "")))
    if s.meta.get("portal_from") != "video" or not source.is_file() or s.values is None:
        return None
    log_video(rec, entity, source)
    seconds = s.time - s.time[0]
    for name, series in (("value", s.values), ("reward", s.rewards)):
        if series is not None:
            rec.send_columns(
                f"{entity}_scores/{name}",
                indexes=[rr.TimeColumn("video_time", duration=seconds[: len(series)])],
                columns=rr.Scalars.columns(scalars=series[: len(seconds)]),
            )
    return entity


def _blueprint(report: dict, videos: list[str] = ()) -> rrb.Blueprint:
    """3D paths and the XY projection on top (and the first video with its learned scores per frame, if any);
    deviation curves and the table below."""
    bars = [rrb.BarChartView(origin=f"/assessment/scores/{k}", name=k) for k in report["scores"]]
    shown = [
        view
        for v in videos
        for view in (
            rrb.Spatial2DView(origin=f"/{v}", name=f"video {v.rsplit('/', 1)[-1]}"),
            rrb.TimeSeriesView(origin=f"/{v}_scores", name="learned reward and value per frame"),
        )
    ]
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                rrb.Spatial3DView(origin="/world", name="paths by learned value (3D)"),
                rrb.Spatial2DView(origin="/assessment/xy", name="XY projection (mm, y up)"),
                *shown,
            ),
            rrb.Horizontal(
                rrb.TimeSeriesView(
                    origin="/assessment/deviation", name="deviation from expert (mm) by % done (timeline percent)"
                ),
                rrb.TextDocumentView(origin="/assessment/summary", name="scores"),
                rrb.Tabs(*bars, name="group means") if bars else rrb.Spacer(),
            ),
        ),
        *([rrb.TimePanel(timeline="video_time", state="collapsed")] if videos else []),  # the video plays
        collapse_panels=True,
    )
