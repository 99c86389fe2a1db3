"""`fastrl export --minari` and `fastrl import --minari`: trajectories with actions to and from Minari datasets."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ..spec import SpecError
from . import SetOpt, app, err, exit_with, load_or_exit, out


@app.command(name="export")
def export(
    trajectories: Annotated[
        list[Path], typer.Argument(metavar="TRAJ", help="trajectory .npz files or folders", show_default=False)
    ],
    minari: Annotated[
        Path, typer.Option(metavar="DIR", help="Minari datasets folder to write into (local)", show_default=False)
    ],
    spec: Annotated[Path, typer.Option(metavar="SPEC", help="the task the trajectories were recorded in")],
    dataset_id: Annotated[str | None, typer.Option(help="Minari dataset id (default fastrl/<spec name>-v0)")] = None,
    set_: SetOpt = None,
) -> None:
    """Write demonstrations or a cohort (trajectories with actions) as a Minari dataset, replayed in SPEC."""
    from ..data.minari_io import export_minari
    from ..data.trajectory import TrajectoryError, load_trajectories
    from ..env.fast_env import FastEnv
    from ..spec import task_hash

    task = load_or_exit(spec, set_)
    trajs, errors = load_trajectories(trajectories)
    for e in errors:
        err.print(e, markup=False)
    if errors:
        raise typer.Exit(code=2)
    ours = task_hash(task.spec)
    other = [t.meta.get("subject", i) for i, t in enumerate(trajs) if t.meta.get("task_hash", ours) != ours]
    if other:
        err.print(
            f"{len(other)} trajectories were recorded in another task than {spec} (e.g. {other[0]})", markup=False
        )
        raise typer.Exit(code=2)
    name = dataset_id or f"fastrl/{task.spec.name}-v0"
    try:
        path = export_minari(FastEnv(task.spec), trajs, minari, name)
    except (TrajectoryError, SpecError, ValueError) as e:
        exit_with(e)
    out.print(f"wrote {len(trajs)} episodes to the Minari dataset {escape(name)} in {escape(str(path))}")
    out.print(
        f"load it with: MINARI_DATASETS_PATH={escape(str(minari))} python -c "
        f"\"import minari; print(minari.load_dataset('{escape(name)}'))\""
    )


@app.command(name="import")
def import_(
    minari: Annotated[Path, typer.Option(metavar="DATASET", help="a Minari dataset folder (written by fastrl export)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="folder for the .npz files")] = Path("imported"),
) -> None:
    """Read a Minari dataset that fastrl exported back into trajectory .npz files."""
    from ..data.minari_io import import_minari
    from ..data.trajectory import TrajectoryError

    try:
        trajs = import_minari(minari)
    except (TrajectoryError, FileNotFoundError, ValueError) as e:
        exit_with(e)
    width = len(str(len(trajs)))
    for i, t in enumerate(trajs):
        name = str(t.meta.get("subject", "episode")).replace("/", "-")
        t.save(output / f"{i:0{width}d}-{name}.npz")
    out.print(f"wrote {len(trajs)} trajectories to {escape(str(output))}")
