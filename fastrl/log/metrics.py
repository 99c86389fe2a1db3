"""Training curves on the `timesteps` timeline and the evaluation summary as markdown."""

from __future__ import annotations

import math

import numpy as np
import rerun as rr


def _finite(value) -> bool:
    """True for a real, finite number."""
    try:
        return value is not None and math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


class TrainingCurves:
    """Writes training metrics under `{root}/<name>`, styling each series once."""

    def __init__(self, rec: rr.RecordingStream, root: str = "metrics/train"):
        self.rec, self.root, self.styled = rec, root, set()
        self.last: int | None = None  # the latest timesteps with a row

    def _seen(self, timesteps) -> None:
        """Remember the latest timesteps logged."""
        self.last = int(timesteps) if self.last is None else max(self.last, int(timesteps))

    def _style(self, name: str) -> str:
        """Entity path of a metric; logs its static SeriesLines the first time."""
        path = f"{self.root}/{name.strip('/')}"
        if path not in self.styled:
            self.rec.log(path, rr.SeriesLines(names=name, widths=1.5), static=True)
            self.styled.add(path)
        return path

    def row(self, timesteps: int, metrics: dict[str, float]) -> None:
        """One value per metric at `timesteps`, through the batcher; None/NaN skipped."""
        self.rec.set_time("timesteps", sequence=int(timesteps))
        self._seen(timesteps)
        try:
            for name, value in metrics.items():
                if _finite(value):
                    self.rec.log(self._style(name), rr.Scalars(float(value)))
        finally:
            self.rec.disable_timeline("timesteps")

    def columns(self, timesteps: np.ndarray, metrics: dict[str, np.ndarray]) -> None:
        """Many rows per metric at once; NaN entries are dropped per metric."""
        ts = np.asarray(timesteps, np.int64)
        if len(ts):
            self._seen(ts.max())
        for name, values in metrics.items():
            v = np.asarray(values, float)  # None -> NaN
            if len(v) != len(ts):
                raise ValueError(f"metric '{name}' has {len(v)} values for {len(ts)} timesteps")
            keep = np.isfinite(v)
            if keep.any():
                self.rec.send_columns(
                    self._style(name),
                    indexes=[rr.TimeColumn("timesteps", sequence=ts[keep])],
                    columns=rr.Scalars.columns(scalars=v[keep]),
                )


def _fmt(x) -> str:
    """A number in a short readable form (strings pass through, None shows as a dash)."""
    if isinstance(x, str):
        return x
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return f"{float(x):.4g}" if _finite(x) else "–"


def summary_markdown(summary: dict, title: str = "Evaluation") -> str:
    """Markdown of the headline figures of `fastrl.runner.train.evaluate.summarize` output."""
    g = summary.get
    lines = [
        f"## {title}",
        "",
        "| figure | value |",
        "|---|---|",
        f"| episodes | {_fmt(g('episodes', 0))} |",
        f"| success rate | {_fmt(100 * g('success_rate', math.nan))} % |",
        f"| subtasks completed | {_fmt(100 * g('subtasks_completed', math.nan))} % |",
        f"| return | {_fmt(g('return_mean', math.nan))} ± {_fmt(g('return_std', math.nan))} |",
        f"| episode time | {_fmt(g('episode_time_mean', math.nan))} s |",
        f"| path length | {_fmt(100 * g('path_length_mean', math.nan))} cm |",
    ]
    feats = g("features_mean") or {}
    if feats:
        lines += [
            "",
            "### Reward features (mean sum per episode)",
            "",
            "| feature | value |",
            "|---|---|",
        ]
        lines += [f"| {k} | {_fmt(v)} |" for k, v in feats.items()]
    eps = g("per_episode") or []
    if eps:
        lines += [
            "",
            "### Episodes",
            "",
            "| # | seed | success | subtasks | return | time (s) | contacts |",
            "|---|---|---|---|---|---|---|",
        ]
        for i, e in enumerate(eps):
            done = f"{_fmt(e.get('subtasks'))}/{_fmt(e.get('subtasks_total'))}"
            cells = [
                i,
                e.get("seed"),
                e.get("success"),
                done,
                e.get("return"),
                e.get("episode_time"),
                e.get("contacts"),
            ]
            lines.append("| " + " | ".join(_fmt(c) for c in cells) + " |")
    return "\n".join(lines) + "\n"
