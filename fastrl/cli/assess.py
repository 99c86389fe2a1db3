"""The paper's protocol on recordings as one command (`fastrl assess`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from . import RunsOpt, SetOpt, app, err, exit_with, out


@app.command(name="assess")
def assess_cohort(
    inputs: Annotated[
        list[Path] | None,
        typer.Argument(metavar="COHORT_DIR...", help="trajectory .npz files or folders", show_default=False),
    ] = None,
    spec: Annotated[
        Path | None, typer.Option("--spec", metavar="SPEC", help="the task the recordings were made in")
    ] = None,
    top: Annotated[int, typer.Option("--top", metavar="K", help="learn from the K best recordings")] = 10,
    by: Annotated[
        str | None,
        typer.Option(
            help="rank by motion (the stopwatch and the motion; the default), time, length (path) or heuristic"
        ),
    ] = None,
    algorithm: Annotated[str, typer.Option(help="airl or gail")] = "airl",
    seeds: Annotated[
        int, typer.Option(help="learn N scorers (train.seed and the next ones): mean, spread and agreement")
    ] = 1,
    address: Annotated[
        str | None,
        typer.Option(
            metavar="ADDR",
            help="learn the seeds at once as Ray tasks, two to a CPU: a cluster's address, or local (this machine)",
        ),
    ] = None,
    set_: SetOpt = None,
    output: Annotated[
        Path | None,
        typer.Option(
            "-o",
            "--output",
            help="JSON report, or a folder for scores.json (CSV, PNGs and .rrd beside it; default RUN/scores.json)",
        ),
    ] = None,
    runs: RunsOpt = Path("runs"),
    pictures: Annotated[bool, typer.Option(help="write the PNG figures and the Rerun recording")] = True,
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
    resume: Annotated[
        Path | None,
        typer.Option(
            metavar="RUN",
            help="continue a stopped assessment in its folder, with its own recordings and options",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Rank recordings, learn reward, value and policy from the best K without their actions, score them all."""
    from ..agents.checkpoint_files import CheckpointMismatch
    from ..atomic import DiskFull
    from ..runner import EvaluationInterrupted, RunInterrupted, RunOutOfSpace
    from ..runner.chosen import DEFAULT_BY
    from ..runner.protocol import ScoringInterrupted, resume_protocol, run_protocol
    from ..spec import SpecError
    from .score import print_report, report_file
    from .stops import report_stop, stop_code

    if resume is not None and (inputs or spec or set_):
        exit_with(ValueError("--resume RUN continues with the assessment's own recordings, spec and --set: give none"))
    if resume is None and not (inputs and spec):
        exit_with(ValueError("give the recordings to assess (COHORT_DIR...) and --spec SPEC, or --resume RUN"))
    try:
        if resume is not None:
            done = resume_protocol(resume, console=err, progress=progress, address=address)
        else:
            done = run_protocol(
                inputs,
                spec,
                top,
                by or DEFAULT_BY,
                algorithm,
                list(set_ or []),
                runs,
                report_file(output),
                console=err,
                progress=progress,
                pictures=pictures,
                seeds=seeds,
                address=address,
            )
    except (RunInterrupted, EvaluationInterrupted, RunOutOfSpace) as stop:
        report_stop(stop, f"fastrl assess --resume {stop.run.parent}")  # a seed's run, in the assessment's folder
    except DiskFull as stop:
        report_stop(stop)
    except ScoringInterrupted as stop:
        err.print(str(stop), markup=False)
        err.print(f"resume with: fastrl assess --resume {stop.run}", markup=False)
        raise typer.Exit(code=stop_code(stop.signal_name)) from None
    except (SpecError, FileNotFoundError, ValueError, CheckpointMismatch) as e:  # RunFileError too
        exit_with(e)
    except KeyboardInterrupt:  # outside a learning run (ranking, scoring, seeds on Ray before any checkpoint)
        err.print("interrupted: run the same command again", markup=False)
        raise typer.Exit(code=130) from None
    report = done.assessment.report
    problems = list(report["problems"])
    problems += [p for p in done.skipped if not any(p.split(":")[0] in q for q in problems)]
    for problem in problems:
        err.print(f"skipped {problem}", markup=False, style="yellow")
    for warning in report["warnings"]:
        err.print(f"note: {warning}", markup=False, style="yellow")
    print_report(report)
    if "seeds" in report:
        print_agreement(report["seeds"])
    out.print(done.why, markup=False)
    for row in done.chosen:
        out.print(
            f"  {row['file']}: heuristic {row['heuristic']:.3g}, subtasks {row['subtasks']:.0%}, "
            f"path {row['path_length']:.3f} m, time {row['time']:.1f} s",
            markup=False,
        )
    out.print(f"scored {len(report['trajectories'])} trajectories; {len(problems)} skipped")
    for learned in done.learned:
        out.print(f"  learned networks: {escape(str(learned))} (fastrl score --run {escape(str(learned))} ...)")
    for kind, path in done.assessment.files.items():
        out.print(f"  {kind}: {escape(str(path))}")


def print_agreement(seeds: dict) -> None:
    """How far the seeds' learned scores agree with each other and with the simple metrics."""
    from rich.table import Table

    simple = list(next(iter(seeds["with_simple_metrics"].values()), {}))
    t = Table(
        title=f"learned scores over seeds {', '.join(map(str, seeds['seeds']))}: Kendall tau",
        caption="seeds that agree make the same ranking, not necessarily a right one (RESULTS: outside cohorts)",
    )
    for col in ("score", "between seeds: mean (min)", *(f"with {s}" for s in simple)):
        t.add_column(col, justify="right")
    for key, a in seeds["agreement"].items():
        between = "-" if a["mean_tau"] is None else f"{a['mean_tau']:.2f} ({a['min_tau']:.2f})"
        cells = ["-" if v is None else f"{v:.2f}" for v in seeds["with_simple_metrics"][key].values()]
        t.add_row(key, between, *cells)
    out.print(t)
