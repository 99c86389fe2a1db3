"""The `fastrl` command line: a thin typer layer over fastrl.spec and fastrl.model."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console
from rich.markup import escape

from ..about import version_line
from ..long_lived import no_collection_at_exit
from ..spec import SpecError, load_spec
from . import typer_flags  # noqa: F401  (before any command: the --help of every one)

if TYPE_CHECKING:
    from ..model import CompiledTask

no_collection_at_exit()

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

SPEC_HELP = "task spec YAML, or a bundled spec's name (tracelines)"
SpecArg = Annotated[Path, typer.Argument(metavar="SPEC", help=SPEC_HELP, show_default=False)]
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
    from ..model import load_task  # imports mujoco: only for commands that need it

    return load_task(path, overrides)


def report(error: SpecError) -> None:
    """Print every issue of a SpecError to stderr, one `FILE:LINE: path: message` line each."""
    for issue in error.errors:
        err.print(str(issue), markup=False)


def exit_with(error: Exception) -> None:
    """Report a user error (spec problems, a missing run) and exit 2, without a traceback."""
    if isinstance(error, SpecError):
        report(error)
    else:
        err.print(str(error), markup=False)
    raise typer.Exit(code=2) from None


def load_or_exit(path: Path, overrides: list[str] | None = None) -> CompiledTask:
    """load(), or print every problem to stderr and exit 2."""
    try:
        return load(path, overrides)
    except SpecError as e:
        report(e)
        raise typer.Exit(code=2) from None


def spec_or_exit(path: Path, overrides: list[str]):
    """The validated spec (not compiled), or every problem printed to stderr and exit 2."""
    try:
        return load_spec(path, overrides)
    except SpecError as e:
        report(e)
        raise typer.Exit(code=2) from None


def with_shortcuts(overrides: list[str] | None, shortcuts: dict) -> list[str]:
    """--set's overrides, then one for each shortcut option given (e.g. --seed 3: train.seed=3)."""
    given = {k: v for k, v in shortcuts.items() if v is not None and v != ""}
    return [*(overrides or []), *(f"{k}={v}" for k, v in given.items())]


def write_text(path: Path, text: str) -> None:
    """Write a file, or exit 1 with a one-line message."""
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as e:
        err.print(f"cannot write {path}: {e.strerror or e}", markup=False)
        raise typer.Exit(code=1) from None


def _version(value: bool) -> None:
    if value:
        out.print(version_line(), markup=False)
        raise typer.Exit()


# --- commands -------------------------------------------------------------------------------


@app.callback()
def main(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="print the name on PyPI and the version"),
    ] = False,
) -> None:
    """FAST arthroscopy tasks: YAML specs compiled to MuJoCo, trained and scored as RL."""


from . import spec_files  # noqa: E402,F401  (check, schema, compile: listed in this order)


@app.command()
def demos(
    source: Annotated[Path | None, typer.Argument(metavar="RUN_DIR", help="a trained run", show_default=False)] = None,
    expert: Annotated[Path | None, typer.Option(metavar="SPEC", help="use the scripted expert on SPEC")] = None,
    n: Annotated[int, typer.Option("-n", min=1, help="number of trajectories")] = 20,
    output: Annotated[Path, typer.Option("-o", "--output", help="folder for the .npz files")] = Path("demos"),
    seed: Annotated[int, typer.Option(help="seed of the first episode")] = 0,
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
    video: Annotated[
        bool, typer.Option("--video", help="also write each one's endoscope video (.mp4) beside it")
    ] = False,
) -> None:
    """Write demonstrations (trajectory .npz files) from a trained run or the scripted expert."""
    from ..runner.train.demos import write_demos

    if (source is None) == (expert is None):
        err.print("give RUN_DIR, or --expert SPEC", markup=False)
        raise typer.Exit(code=2)
    if output.exists() and not output.is_dir():
        err.print(f"-o {output}: a file is there; give a folder for the .npz files", markup=False)
        raise typer.Exit(code=2)
    try:
        paths = write_demos(output, n, seed, run=source, expert_spec=expert, progress=progress, video=video)
    except (SpecError, FileNotFoundError) as e:
        exit_with(e)
    out.print(f"wrote {len(paths)} trajectories to {escape(str(output))}")


RunsOpt = Annotated[Path, typer.Option("--runs", help="root folder of run directories")]


@app.command()
def run(
    spec: Annotated[Path | None, typer.Argument(metavar="SPEC", help=SPEC_HELP, show_default=False)] = None,
    set_: SetOpt = None,
    algo: Annotated[str | None, typer.Option(help="shortcut for --set train.algo=...")] = None,
    seed: Annotated[int | None, typer.Option(help="shortcut for --set train.seed=...")] = None,
    timesteps: Annotated[int | None, typer.Option(help="shortcut for --set train.timesteps=...")] = None,
    resume: Annotated[Path | None, typer.Option(help="continue RUN_DIR from its newest checkpoint")] = None,
    runs: RunsOpt = Path("runs"),
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
) -> None:
    """Train an agent on a spec, evaluate it and record everything to RUN_DIR/recording.rrd.

    With an `irl` section (algorithm gail, airl or bc) the agent learns from demonstrations instead.
    """
    overrides = with_shortcuts(set_, {"train.algo": algo, "train.seed": seed, "train.timesteps": timesteps})
    if (spec is None) == (resume is None):
        err.print("give a SPEC to start a run, or --resume RUN_DIR to continue one (not both)", markup=False)
        raise typer.Exit(code=2)
    from .training import train_and_report

    train_and_report(spec, overrides, resume, runs, progress, timesteps)


@app.command()
def irl(
    spec: SpecArg,
    demos: Annotated[
        Path | None,
        typer.Option(metavar="DIR", help="demonstrations (.npz); default: write scripted-expert ones into the run"),
    ] = None,
    algorithm: Annotated[str | None, typer.Option(help="gail, airl or bc (default: the spec's, else airl)")] = None,
    generator: Annotated[str | None, typer.Option(help="PPO or SAC (shortcut for --set train.algo=...)")] = None,
    set_: SetOpt = None,
    seed: Annotated[int | None, typer.Option(help="shortcut for --set train.seed=...")] = None,
    timesteps: Annotated[int | None, typer.Option(help="shortcut for --set train.timesteps=...")] = None,
    runs: RunsOpt = Path("runs"),
    progress: Annotated[bool, typer.Option(help="show the progress bar")] = True,
) -> None:
    """Learn a reward and a policy from demonstrations (GAIL, AIRL) or clone them (BC), then evaluate."""
    overrides = list(set_ or [])
    if algorithm is None and spec_or_exit(spec, overrides).irl.algorithm == "none":
        algorithm = "airl"
    shortcuts = {"irl.algorithm": algorithm, "irl.demonstrations.path": demos, "train.algo": generator}
    overrides = with_shortcuts(overrides, shortcuts | {"train.seed": seed, "train.timesteps": timesteps})
    from .training import train_and_report

    train_and_report(spec, overrides, None, runs, progress, timesteps)


@app.command(name="eval")
def eval_(
    run_dir: Annotated[Path | None, typer.Argument(metavar="RUN_DIR", show_default=False)] = None,
    expert: Annotated[Path | None, typer.Option(metavar="SPEC", help="evaluate the scripted expert on SPEC")] = None,
    episodes: Annotated[int | None, typer.Option(min=1, help="number of episodes (default: the spec's)")] = None,
    output: Annotated[Path | None, typer.Option("-o", "--output", help="write the figures as JSON")] = None,
) -> None:
    """Re-evaluate a saved run (deterministic episodes), or the scripted expert on a spec."""
    from .training import eval_and_report

    eval_and_report(run_dir, expert, episodes, output)


@app.command()
def view(
    run_dir: Annotated[Path, typer.Argument(metavar="RUN_DIR", show_default=False)],
    web: Annotated[bool, typer.Option("--web", help="serve RUN_DIR or SWEEP_DIR to a browser on localhost")] = False,
    port: Annotated[int, typer.Option(help="with --web: the web viewer's port")] = 9090,
) -> None:
    """Open a run's recording in the Rerun viewer (or say how, where there is no display)."""
    from ..runner.runs.runfiles import recording_fault
    from .runcheck import check_run

    if (run_dir / "recording.rrd").is_file():  # a run directory (a sweep folder is served as it is)
        check_run(run_dir, {"recording.rrd"})
    elif run_dir.is_file() and (fault := recording_fault(run_dir)):
        err.print(f"{run_dir}: {fault}; mend it with: fastrl repair {run_dir.parent}", markup=False)
        raise typer.Exit(code=2)
    if web:
        from .web import view_web

        return view_web(run_dir, port)
    from .web import view_local

    view_local(run_dir)


# commands in their own modules register themselves on `app`
from . import assess, cohort, datasets, poses, run_list, score, stops, sweep, trainee, videos  # noqa: E402,F401
