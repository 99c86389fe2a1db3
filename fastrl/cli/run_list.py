"""`fastrl runs`: the runs under a folder with their headline figures, newest first."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from . import RunsOpt, app, out


@app.command(name="runs")
def runs_(
    root: RunsOpt = Path("runs"),
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of a table")] = False,
) -> None:
    """List runs with their headline figures, newest first."""
    from rich.table import Table

    from ..runner.runs.rundir import list_runs

    rows = list_runs(root)
    if as_json:
        typer.echo(json.dumps(rows, indent=2))
        return
    if not rows:
        out.print(f"no runs under {escape(str(root))}")
        return
    table = Table(title=f"runs under {escape(str(root))}", box=None, pad_edge=False, collapse_padding=True)
    # The run's name holds its spec, algorithm and seed (spec/<time>-<algo>-s<seed>): kept whole, on one line.
    longest = max(len(Path(r["run"]).relative_to(root).as_posix()) for r in rows)
    table.add_column("run", no_wrap=True, min_width=min(longest, 44))
    table.add_column("status", no_wrap=True, overflow="ellipsis", max_width=10)
    for col in ("steps", "wall", "success", "subtasks"):
        table.add_column(col, justify="right", no_wrap=True)
    for r in rows:
        pct = lambda v: "-" if v is None else f"{v:.0%}"  # noqa: E731
        table.add_row(
            escape(Path(r["run"]).relative_to(root).as_posix()),
            escape(r["status"]),
            _count(r["timesteps"]),
            _duration(r["wall_s"]),
            pct(r["success"]),
            pct(r["subtasks"]),
        )
    out.print(table)
    for r in rows:
        for problem in r["problems"]:
            out.print(escape(problem))


def _count(n: int | None) -> str:
    """A step count in a few characters: 16384 -> 16k, 1500000 -> 1.5M."""
    if not n:
        return "-"
    if n >= 1_000_000:
        return f"{n / 1e6:.3g}M"
    return f"{n / 1e3:.3g}k" if n >= 1000 else str(n)


def _duration(seconds: float | None) -> str:
    """Wall time in a few characters: 42s, 12m, 3.5h."""
    if seconds is None:
        return "-"
    if seconds < 120:
        return f"{seconds:.0f}s"
    return f"{seconds / 60:.0f}m" if seconds < 7200 else f"{seconds / 3600:.1f}h"
