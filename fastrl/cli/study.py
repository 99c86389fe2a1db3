"""`fastrl run` on a spec with a study: run or continue it, print Table 3."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.markup import escape

from ..spec import SpecError
from . import err, exit_with, out


def study_and_report(plan, runs: Path, progress: bool) -> None:
    """Run (or continue) the planned study and print its Table 3."""
    from ..runner import RunInterrupted, RunOutOfSpace
    from ..runner.runs.runfiles import STUDY_RESULT
    from ..runner.train.training import train

    try:
        run_dir = train(plan, runs, out, progress)
    except RunInterrupted as stop:
        run_dir = stop.run.parent
        err.print(
            f"interrupted in {stop.run.name} at {stop.timesteps} timesteps; what is done is saved in {run_dir}",
            markup=False,
        )
        err.print(f"continue with: fastrl run --resume {run_dir}", markup=False)
        raise typer.Exit(code=130) from None
    except KeyboardInterrupt:
        err.print("interrupted; what is done is saved: continue with fastrl run --resume RUN_DIR", markup=False)
        raise typer.Exit(code=130) from None
    except RunOutOfSpace as stop:
        err.print(stop.sentence() + ".", markup=False)
        err.print(f"continue with: fastrl run --resume {stop.run.parent}", markup=False)
        raise typer.Exit(code=1) from None
    except (SpecError, FileNotFoundError) as e:
        exit_with(e)
    print_table3(json.loads((run_dir / STUDY_RESULT).read_text()))
    out.print(
        f"study saved in {escape(str(run_dir))}: {STUDY_RESULT}, table3.png; "
        f"view it with: rerun {escape(str(run_dir / 'recording.rrd'))}"
    )


def print_table3(result: dict) -> None:
    """Table 3: Spearman's rho (p-value) of learned reward and value against economy and safety."""
    from rich.table import Table

    from ..log.study import PANELS

    def cell(c: dict) -> str:
        return "-" if c["rho"] is None else f"{c['rho']:.2f} ({c['p']:.0e})"

    table = Table(
        title=f"learned scores of {result['n']} procedures against economy and safety (Spearman's rho, p-value)"
    )
    table.add_column("model", no_wrap=True, min_width=9)
    for k, m in PANELS:
        table.add_column(f"{k}\nvs {m}", justify="right", no_wrap=True)
    for algo, cells in result["table3"].items():
        if algo != "heuristic":
            table.add_row(algo.upper(), *(cell(cells[f"{k}-{m}"]) for k, m in PANELS))
    h = result["table3"]["heuristic"]
    table.add_row("heuristic", cell(h["heuristic-economy"]), cell(h["heuristic-safety"]), "", "")
    out.print(table)
