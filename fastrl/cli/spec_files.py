"""Commands on spec files: check them, export their JSON Schema, compile one to MJCF."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ..bundled import find_spec
from ..spec import SpecError, json_schema, read_yaml
from ..spec.migrate import OLD_LAYOUT, in_old_layout
from . import SetOpt, SpecArg, app, load, load_or_exit, out, report, write_text


@app.command()
def check(
    specs: Annotated[list[Path], typer.Argument(metavar="SPEC", help="task spec YAML files", show_default=False)],
    set_: SetOpt = None,
) -> None:
    """Validate and compile task specs; print FILE:LINE errors and exit 2 if any is bad."""
    bad = 0
    for path in specs:
        try:
            task = load(path, set_)
        except SpecError as e:
            report(e)
            bad += 1
            continue
        spec = task.spec
        summary = f"{spec.task.kind}, {len(task.targets)} subtasks, {spec.actions.mode}"
        out.print(f"[green]ok[/]  {escape(str(path))}  ({summary})")
        if in_old_layout(read_yaml(find_spec(path))[0]):
            out.print(f"    {OLD_LAYOUT}", markup=False)
    if bad:
        raise typer.Exit(code=2)


@app.command()
def schema(
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="write to this file", show_default=False)
    ] = None,
) -> None:
    """Print the JSON Schema of task specs (for editors), or write it to a file."""
    text = json.dumps(json_schema(), indent=2) + "\n"
    if output is None:
        typer.echo(text, nl=False)  # plain: no rich markup or wrapping inside the JSON
        return
    write_text(output, text)
    out.print(f"wrote {output}", markup=False)


@app.command(name="compile")
def compile_(
    spec: SpecArg,
    output: Annotated[Path, typer.Option("-o", "--output", help="MJCF file to write", show_default=False)],
    set_: SetOpt = None,
) -> None:
    """Compile a task spec and write the MuJoCo model (MJCF XML)."""
    task = load_or_exit(spec, set_)
    write_text(output, task.xml)
    m = task.model
    out.print(
        f"wrote {escape(str(output))}  (nbody {m.nbody}, njnt {m.njnt}, ngeom {m.ngeom}, "
        f"nu {m.nu}, timestep {m.opt.timestep:g} s)"
    )
