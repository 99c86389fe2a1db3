"""The `fastrl` command line: a thin typer layer over fastrl.spec and fastrl.model."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console
from rich.markup import escape

from . import __version__
from .spec import SpecError, SpecIssue, json_schema, load_spec

if TYPE_CHECKING:
    from .model import CompiledTask

app = typer.Typer(
    name="fastrl",
    help="FAST arthroscopy tasks: YAML specs compiled to MuJoCo, trained and scored as RL.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)

# soft_wrap: never re-wrap (a FILE:LINE message stays one line); emoji off (":100:" is a line).
# Rich drops colour by itself when the stream is not a terminal (CI, pipes, CliRunner).
out = Console(soft_wrap=True, emoji=False, highlight=False)
err = Console(stderr=True, soft_wrap=True, emoji=False, highlight=False)

SpecArg = Annotated[Path, typer.Argument(metavar="SPEC", help="task spec YAML", show_default=False)]
SetOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        metavar="KEY=VALUE",
        show_default=False,
        help="override a spec field, e.g. --set task.cue.dwell=1.0 (repeatable)",
    ),
]


# --- shared helpers -------------------------------------------------------------------------


def load(path: Path, overrides: list[str] | None = None) -> CompiledTask:
    """Validate and compile a spec; every problem (MuJoCo compile errors too) raises SpecError."""
    from .model import compile_task  # imports mujoco: only for commands that need it

    spec = load_spec(path, overrides or ())
    try:
        return compile_task(spec)
    except ValueError as e:  # mujoco reports compile errors as ValueError
        detail = " ".join(str(e).split())
        raise SpecError(
            [SpecIssue(str(path), None, "", f"MuJoCo cannot compile the model: {detail}")]
        ) from None


def report(error: SpecError) -> None:
    """Print every issue of a SpecError to stderr, one `FILE:LINE: path: message` line each."""
    for issue in error.errors:
        err.print(str(issue), markup=False)


def load_or_exit(path: Path, overrides: list[str] | None = None) -> CompiledTask:
    """load(), or print every problem to stderr and exit 2."""
    try:
        return load(path, overrides)
    except SpecError as e:
        report(e)
        raise typer.Exit(code=2) from None


def write_text(path: Path, text: str) -> None:
    """Write a file, or exit 1 with a one-line message."""
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as e:
        err.print(f"cannot write {path}: {e.strerror or e}", markup=False)
        raise typer.Exit(code=1) from None


def _version(value: bool) -> None:
    if value:
        out.print(f"fastrl {__version__}", markup=False)
        raise typer.Exit()


# --- commands -------------------------------------------------------------------------------


@app.callback()
def main(
    version: Annotated[
        bool,
        typer.Option(
            "--version", callback=_version, is_eager=True, help="print the version and exit"
        ),
    ] = False,
) -> None:
    """FAST arthroscopy tasks: YAML specs compiled to MuJoCo, trained and scored as RL."""


@app.command()
def check(
    specs: Annotated[
        list[Path], typer.Argument(metavar="SPEC", help="task spec YAML files", show_default=False)
    ],
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
    output: Annotated[
        Path, typer.Option("-o", "--output", help="MJCF file to write", show_default=False)
    ],
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


if __name__ == "__main__":
    app()
