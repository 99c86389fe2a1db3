"""`fastrl sweep`: a grid of configurations x seeds on Ray Tune, each trial an ordinary run; results table."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ..spec import SpecError
from . import SPEC_HELP, SetOpt, app, err, exit_with, out


def _fmt(mean, sd, pct: bool) -> str:
    """mean +- sd, as percentages or plain numbers; '-' when nothing finished."""
    if mean is None:
        return "-"
    return f"{mean:.0%} ± {sd:.0%}" if pct else f"{mean:.1f} ± {sd:.1f}"


def print_results(summary: dict) -> None:
    """The per-configuration table, the best configuration and the failed trials."""
    table = Table(title=f"sweep of {summary['spec']}: mean ± sd over seeds {summary['seeds']}")
    for col in ("configuration", "seeds", "success", "subtasks", "return", "wall (s)"):
        table.add_column(col, justify="left" if col == "configuration" else "right", overflow="fold")
    for r in summary["rows"]:
        table.add_row(
            escape(r["config"]),
            f"{r['seeds']}/{r['of']}",
            _fmt(r["success_mean"], r["success_sd"], True),
            _fmt(r["subtasks_mean"], r["subtasks_sd"], True),
            _fmt(r["return_mean"], r["return_sd"], False),
            _fmt(r["wall_s_mean"], r["wall_s_sd"], False),
        )
    out.print(table)
    best = summary["best"]
    if best:
        setting = " ".join(f"{k}={v}" for k, v in best["setting"].items()) or "(the base spec)"
        out.print(f"best configuration: {escape(best['config'])}  ({escape(setting)})")
    for f in summary["failed"]:
        err.print(f"trial {f['trial']} failed twice: {f['error']}", markup=False)


@app.command()
def sweep(
    spec: Annotated[Path | None, typer.Argument(metavar="SPEC", help=SPEC_HELP, show_default=False)] = None,
    grid: Annotated[
        list[str] | None,
        typer.Option(metavar="KEY=V1,V2", show_default=False, help="a spec field and its values (repeatable)"),
    ] = None,
    seeds: Annotated[str, typer.Option(help="seeds of every configuration")] = "0,1,2",
    set_: SetOpt = None,
    address: Annotated[
        str | None, typer.Option(help="Ray cluster to run on (default: RAY_ADDRESS, else a local Ray)")
    ] = None,
    cpus_per_trial: Annotated[int, typer.Option(help="CPUs (and torch threads) per trial")] = 1,
    output: Annotated[
        Path | None,
        typer.Option("-o", "--output", help="sweep folder (default runs/<spec>/<time>-sweep)", show_default=False),
    ] = None,
    resume: Annotated[
        Path | None, typer.Option(metavar="SWEEP_DIR", help="run the unfinished trials of a sweep", show_default=False)
    ] = None,
    runs: Annotated[Path, typer.Option("--runs", help="root folder of run directories")] = Path("runs"),
) -> None:
    """Run a grid of spec settings x seeds on Ray Tune; print and write the results table, best and figure."""
    from ..runner.sweep.plan import SweepError, create_sweep, parse_grid, parse_seeds, read_manifest
    from ..runner.sweep.table import write_results
    from ..runner.sweep.tune import run_sweep

    if (spec is None) == (resume is None):
        err.print("give a SPEC and --grid to start a sweep, or --resume SWEEP_DIR (not both)", markup=False)
        raise typer.Exit(code=2)
    if resume is not None and (grid or set_):
        err.print("--resume runs the sweep's own grid and settings: drop --grid and --set", markup=False)
        raise typer.Exit(code=2)
    try:
        if resume is None:
            from ..spec import load_spec

            name = load_spec(spec, set_ or []).name
            stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
            folder = output or runs / name / f"{stamp}-sweep"
            folder = create_sweep(
                spec, list(set_ or []), parse_grid(grid or []), parse_seeds(seeds), cpus_per_trial, folder
            )
        else:
            folder = resume
            read_manifest(folder)
        out.print(f"sweep folder {escape(str(folder))}")
        failed = run_sweep(folder, address, out)
    except (SpecError, SweepError, FileNotFoundError) as e:
        exit_with(e)
    except KeyboardInterrupt:
        err.print(f"interrupted; continue with: fastrl sweep --resume {folder}", markup=False)
        raise typer.Exit(code=130) from None
    summary = write_results(folder, failed)
    print_results(summary)
    out.print(f"wrote {escape(str(folder))}/results.json, results.csv, results.png")
    if failed:
        raise typer.Exit(code=1)
