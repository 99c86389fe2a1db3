"""Synthetic trainee cohorts (`fastrl cohort`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from . import SetOpt, SpecArg, app, err, load_or_exit, out


@app.command()
def cohort(
    spec: SpecArg,
    levels: Annotated[int, typer.Option(help="skill levels: 1 is the novice, LEVELS expert-like")] = 5,
    per_level: Annotated[int, typer.Option(help="trajectories (subjects) per level")] = 10,
    output: Annotated[Path, typer.Option("-o", "--output", help="folder for the .npz files")] = Path("cohort"),
    seed: Annotated[int, typer.Option(help="seed of the first trajectory (then seed+1, ...)")] = 0,
    families: Annotated[
        str,
        typer.Option(help="deficit families the subjects mix, comma-separated, or 'all' (fastrl.data.families)"),
    ] = "classic",
    set_: SetOpt = None,
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
    video: Annotated[
        bool, typer.Option("--video", help="also write each one's endoscope video (.mp4) beside it")
    ] = False,
) -> None:
    """Write a synthetic trainee cohort (DIR/<subject>.npz) and print its figures by skill level."""
    from rich.progress import Progress

    from ..data.cohort import level_table, make_cohort, replayed_figures
    from ..data.families import family_names, foreign_family
    from ..data.render_video import write_trajectory_video
    from ..data.video_import import endoscope_size
    from ..env.fast_env import FastEnv

    if levels < 2 or per_level < 1:
        err.print(f"need --levels >= 2 and --per-level >= 1, got {levels} and {per_level}", markup=False)
        raise typer.Exit(code=2)
    try:
        mixed = family_names(families)
    except ValueError as e:
        err.print(f"--families: {e}", markup=False)
        raise typer.Exit(code=2) from None
    task = load_or_exit(spec, set_)
    if task.spec.actions.mode != "discrete":
        err.print(
            f"{spec}: synthetic trainees act with discrete actions; use --set actions.mode=discrete", markup=False
        )
        raise typer.Exit(code=2)
    w, h = endoscope_size(task.spec)
    env = FastEnv(task.spec, width=w, height=h)
    problem = foreign_family(mixed, bool(env.task.instruments))
    if problem:
        err.print(f"{spec}: --families: {problem}", markup=False)
        raise typer.Exit(code=2)
    rows = []
    with Progress(disable=not progress) as bar:
        job = bar.add_task(f"cohort of {task.spec.name}", total=levels * per_level)
        for traj in make_cohort(task.spec, levels, per_level, seed, env=env, families=mixed):
            try:
                path = traj.save(output / f"{traj.meta['subject']}.npz")
                if video:
                    write_trajectory_video(env, traj, path.with_suffix(".mp4"))
            except OSError as e:
                err.print(f"cannot write to {output}: {e.strerror or e}", markup=False)
                raise typer.Exit(code=1) from None
            rows.append({"skill": traj.meta["skill"], **replayed_figures(env, traj)})
            bar.advance(job)
    out.print(f"wrote {len(rows)} trajectories to {escape(str(output))}")
    print_levels(level_table(rows), task.spec.name)


def print_levels(table: list[dict], name: str) -> None:
    """Mean ± sd of heuristic return, subtasks and duration per skill level."""
    from rich.table import Table

    t = Table(title=f"{escape(name)}: synthetic trainees by skill level (figures recomputed by replay)")
    for col in ("level", "n", "heuristic return", "subtasks", "duration (s)"):
        t.add_column(col, justify="right")
    for e in table:
        t.add_row(
            str(e["skill"]),
            str(e["n"]),
            f"{e['return']:.1f} ± {e['return_sd']:.1f}",
            f"{e['subtasks']:.1f} ± {e['subtasks_sd']:.1f}",
            f"{e['duration']:.1f} ± {e['duration_sd']:.1f}",
        )
    out.print(t)
