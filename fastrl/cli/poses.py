"""Tracked scope poses to trajectories (`fastrl import-poses`)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from . import SpecArg, app, err, load_or_exit, out


@app.command(name="import-poses")
def import_poses_(
    spec: SpecArg,
    csv_file: Annotated[Path, typer.Argument(metavar="FILE.csv", help="tracked scope poses", show_default=False)],
    output: Annotated[
        Path | None,
        typer.Option(
            "-o", "--output", help="trajectory .npz, or a folder for it (default: FILE.npz)", show_default=False
        ),
    ] = None,
    subject: Annotated[str | None, typer.Option(help="who held the scope")] = None,
    skill: Annotated[
        str | None,
        typer.Option(help="skill label, if known: a number (higher = more skilled) is ranked by `fastrl score`"),
    ] = None,
    source: Annotated[str, typer.Option(help="agent, expert, human or synthetic")] = "human",
    seed: Annotated[int | None, typer.Option(help="episode seed for replay (avatar jitter of the session)")] = None,
    tolerance_mm: Annotated[float, typer.Option(help="how far the shaft axis may miss the portal point")] = 2.0,
    tolerance_deg: Annotated[float, typer.Option(help="how far the orientation may tilt from portal -> tip")] = 5.0,
    max_rejected: Annotated[float, typer.Option(help="largest fraction of samples that may be rejected")] = 0.2,
    resample: Annotated[
        bool, typer.Option(help="resample to the spec's control rate (replay takes one sample per control step)")
    ] = True,
) -> None:
    """Convert tracked scope (and instrument) poses (CSV) into a trajectory through inverse portal kinematics."""
    from ..data import TrajectoryError
    from ..data.poses import PoseError, import_poses

    target = output_path(csv_file, output)
    task = load_or_exit(spec)
    meta = {"source": source}
    meta.update(
        {k: v for k, v in (("subject", subject), ("skill", _number_or_text(skill)), ("seed", seed)) if v is not None}
    )
    hz = task.spec.episode.control_hz if resample else None
    try:
        traj, report = import_poses(task, csv_file, meta, tolerance_mm, tolerance_deg, max_rejected, hz)
    except PoseError as e:
        err.print(str(e), markup=False)
        for line in e.details:
            err.print(line, markup=False)
        raise typer.Exit(code=2) from None
    except TrajectoryError as e:
        err.print(f"{csv_file}: {e}", markup=False)
        raise typer.Exit(code=2) from None
    for line in report:
        out.print(line, markup=False)
    try:
        traj.save(target)
    except OSError as e:
        err.print(f"cannot write {target}: {e.strerror or e}", markup=False)
        raise typer.Exit(code=1) from None
    out.print(
        f"wrote {escape(str(target))}  ({len(traj.time)} samples, {traj.time[-1]:.2f} s, "
        f"source {escape(str(traj.meta['source']))})"
    )


def output_path(csv_file: Path, output: Path | None) -> Path:
    """Where the trajectory goes: -o FILE.npz, FILE.npz inside an -o folder, else beside the CSV; exit 2 if not .npz."""
    if output is None:
        return csv_file.with_suffix(".npz")
    if output.is_dir():
        return output / csv_file.with_suffix(".npz").name
    if output.suffix != ".npz":
        err.print(f"-o {output}: a trajectory file name ends in .npz (or give an existing folder)", markup=False)
        raise typer.Exit(code=2)
    return output


def _number_or_text(label: str | None):
    """A skill label as a number where it is one (so it can be ranked), else the text."""
    if label is None:
        return None
    try:
        value = float(label)
    except ValueError:
        return label
    if not math.isfinite(value):
        return label  # "nan", "inf": a label, not a number to rank
    return int(value) if value.is_integer() else value
