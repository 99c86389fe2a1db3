"""Before a command uses a run: name its damaged files in one line each; exit 2 if one it needs is damaged."""

from __future__ import annotations

from pathlib import Path

import typer

from . import err


def check_run(run: Path, needed: set[str], checkpoints: bool = True) -> None:
    """Print a note per damaged file of `run`; exit 2 naming the first damaged one in `needed` (no traceback)."""
    from ..runner.runs.runfiles import RunFileError, require

    run = Path(run)
    if not run.is_dir():
        return
    try:
        notes = require(run, needed, checkpoints)
    except RunFileError as e:
        err.print(str(e), markup=False)
        raise typer.Exit(code=2) from None
    for problem in notes:
        err.print(f"note: {problem}", markup=False, style="yellow")
