"""Scoring trainee trajectories (`fastrl score`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from . import app, err, exit_with, out


@app.command()
def score(
    inputs: Annotated[
        list[Path],
        typer.Argument(metavar="TRAJ_OR_DIR...", help="trajectory .npz files or folders", show_default=False),
    ],
    run: Annotated[
        Path | None,
        typer.Option(
            "--run", metavar="RUN_DIR", help="a run: its spec, and after inverse RL its learned reward and value"
        ),
    ] = None,
    spec: Annotated[
        Path | None,
        typer.Option("--spec", metavar="SPEC", help="score without a run (heuristic and kinematic scores only)"),
    ] = None,
    output: Annotated[
        Path | None,
        typer.Option(
            "-o",
            "--output",
            help="JSON report, or a folder for scores.json (CSV, PNGs and .rrd beside it; "
            "default RUN_DIR/assessment/scores.json)",
        ),
    ] = None,
    references: Annotated[int, typer.Option(min=1, help="episodes per normalisation reference")] = 3,
    pictures: Annotated[bool, typer.Option(help="write the PNG figures and the Rerun recording")] = True,
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
    address: Annotated[
        str | None,
        typer.Option(
            "--address", metavar="RAY", help="score on this Ray cluster ('local': start one); same paths on every node"
        ),
    ] = None,
    fresh: Annotated[
        bool, typer.Option(help="score every file again (default: skip those already in the report's journal)")
    ] = False,
) -> None:
    """Score trajectories by replay: heuristic and learned reward, learned value, length, time, smoothness."""
    from ..long_lived import long_lived
    from ..runner.score.assessment import assess
    from ..spec import SpecError

    if (run is None) == (spec is None):
        err.print("give --run RUN_DIR, or --spec SPEC", markup=False)
        raise typer.Exit(code=2)
    output = report_file(output)
    if run is not None:
        from .runcheck import check_run

        check_run(run, {"spec.yaml"})
    try:
        with long_lived():  # the libraries imported so far: no full collection scans them again
            result = assess(
                inputs,
                run=run,
                spec_path=spec,
                output=output,
                reference_episodes=references,
                pictures=pictures,
                console=err,
                progress=progress,
                address=address,
                fresh=fresh,
            )
    except (SpecError, FileNotFoundError, ValueError) as e:
        exit_with(e)
    except KeyboardInterrupt:
        from ..runner.score.assessment import outputs_for

        journal = outputs_for(output, run)["journal"]
        err.print(f"interrupted: the files scored so far are kept in {journal}", markup=False)
        err.print("run the same command again to score the rest", markup=False)
        raise typer.Exit(code=130) from None
    report = result.report
    for problem in report["problems"]:
        err.print(f"skipped {problem}", markup=False, style="yellow")
    for warning in report["warnings"]:
        err.print(f"note: {warning}", markup=False, style="yellow")
    if not report["trajectories"]:
        err.print("no trajectory could be scored", markup=False)
        raise typer.Exit(code=2)
    print_report(report)
    n, secs = len(report["trajectories"]), result.seconds["scoring"]
    resumed = f" ({result.resumed} read from the journal)" if result.resumed else ""
    out.print(f"scored {n} trajectories{resumed} in {secs:.2f} s (replay included); {len(report['problems'])} skipped")
    for kind, path in result.files.items():
        out.print(f"  {kind}: {escape(str(path))}")


def report_file(output: Path | None) -> Path | None:
    """The JSON report's path: `output` itself, or scores.json in it where it is a folder or has no suffix."""
    if output is not None and (output.is_dir() or not output.suffix):
        return output / "scores.json"
    return output


def print_report(report: dict) -> None:
    """The per-group table and, where labels exist, the ranking table."""
    keys = report["scores"]
    table = Table(title=f"scores by {report['grouped_by']} (mean ± sd)")
    table.add_column(report["grouped_by"])
    table.add_column("n", justify="right")
    for k in keys:
        table.add_column(k, justify="right")
    for g in report["groups"]:
        table.add_row(
            escape(str(g["subject"])),
            str(g["n"]),
            *["-" if g[k] is None else f"{g[k]:.3g} ± {g[k + '_sd']:.2g}" for k in keys],
        )
    out.print(table)
    out.print(report["normalisation"], style="dim")
    if report["ranking"]:
        rank = Table(title="ranking against skill labels")
        for col in ("score", "Spearman rho [95% CI]", "Kendall tau-b [95% CI]", "levels in order"):
            rank.add_column(col)
        for k, r in report["ranking"].items():
            rank.add_row(
                k,
                _stat(r["spearman"], r["spearman_ci"]),
                _stat(r["kendall_tau_b"], r["kendall_ci"]),
                "yes" if r["levels_in_order"] else "no",
            )
        out.print(rank)


def _stat(value, ci) -> str:
    """A statistic with its interval, or a dash."""
    if value is None:
        return "-"
    return f"{value:.2f}" + (f" [{ci[0]:.2f}, {ci[1]:.2f}]" if ci else "")
