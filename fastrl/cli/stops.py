"""Stops on the command line: exit codes and messages for signals and a full disk; `fastrl repair RUN_DIR`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from . import app, err, out


def stop_code(signal_name: str) -> int:
    """The shell's exit status for a stop by a signal: 128 + its number (130 Ctrl-C, 143 SIGTERM)."""
    return 143 if signal_name == "SIGTERM" else 130


def report_stop(stop: Exception, resume: str | None = None) -> None:
    """A stopped run in plain lines, the last one how to resume it (`resume`: the command, if not `fastrl run
    --resume RUN`); exit 128 + the signal, or 1 for a full disk."""
    from ..atomic import DiskFull
    from ..runner import EvaluationInterrupted, RunInterrupted, RunOutOfSpace

    if isinstance(stop, RunOutOfSpace):
        report_out_of_space(stop, resume)
    if isinstance(stop, DiskFull):  # before the run started (its spec, its metadata)
        err.print(f"{stop}.", markup=False)
        raise typer.Exit(code=1)
    if isinstance(stop, RunInterrupted):
        saved = f"stopped at {stop.timesteps} timesteps; checkpoint and recording saved in {stop.run}"
    elif isinstance(stop, EvaluationInterrupted):
        saved = f"evaluation stopped; the trained policy is saved in {stop.run}/final"
    err.print(f"{stop.signal_name}: {saved}", markup=False)
    err.print(f"resume with: {resume or f'fastrl run --resume {stop.run}'}", markup=False)
    raise typer.Exit(code=stop_code(stop.signal_name))


def report_out_of_space(stop, resume: str | None = None) -> None:
    """Say in plain sentences that the disk filled, what the recording holds and how to go on; exit 1."""
    err.print(stop.sentence() + ".", markup=False)
    if stop.recording_whole:
        err.print(f"the recording {stop.run}/recording.rrd is valid up to its last complete chunk", markup=False)
    else:
        err.print(
            f"the recording {stop.run}/recording.rrd was cut short; resuming (or: fastrl repair {stop.run}) "
            "rewrites it from its complete chunks",
            markup=False,
        )
    err.print(f"resume with: {resume or f'fastrl run --resume {stop.run}'}", markup=False)
    raise typer.Exit(code=1)


@app.command()
def repair(run_dir: Annotated[Path, typer.Argument(metavar="RUN_DIR", show_default=False)]) -> None:
    """Rewrite recordings cut short by a kill or a full disk from their complete chunks; name bad checkpoints."""
    from ..agents.sb3 import checkpoint_problem
    from ..atomic import DiskFull
    from ..log.recording import repair_recording
    from ..runner.runs.rundir import latest_checkpoint, rebuild_meta
    from ..runner.runs.runfiles import RunFileError, read_eval, read_meta, read_run_spec

    try:
        read_run_spec(run_dir)
    except (FileNotFoundError, RunFileError) as e:
        err.print(str(e), markup=False)
        raise typer.Exit(code=2) from None
    try:
        read_meta(run_dir)
    except RunFileError as e:
        kept = rebuild_meta(run_dir)
        out.print(f"rebuilt  {escape(str(run_dir / 'meta.json'))} ({escape(e.problem.fault)}; kept as {kept.name})")
    if (run_dir / "eval.json").exists():
        try:
            read_eval(run_dir)
        except RunFileError as e:
            out.print(f"damaged  {escape(str(e))}")
    for rrd in sorted(run_dir.glob("recording*.rrd")):
        try:
            fixed = repair_recording(rrd)
        except (DiskFull, ValueError) as e:
            err.print(str(e), markup=False)
            raise typer.Exit(code=1) from None
        out.print(f"{'repaired' if fixed else 'valid'}  {escape(str(rrd))}")
    skipped: list[str] = []
    ckpt = latest_checkpoint(run_dir, skipped)
    for message in skipped:
        out.print(f"damaged checkpoint (resume passes over it): {escape(message)}")
    if (run_dir / "final").exists() and (fault := checkpoint_problem(run_dir / "final")):
        out.print(
            f"damaged final policy (fastrl eval uses the newest whole checkpoint): {run_dir / 'final'}: {fault}",
            markup=False,
        )
    out.print(f"resume from: {escape(str(ckpt))}" if ckpt else "no whole checkpoint: resume starts from 0 timesteps")
