"""Trainee in the loop: `fastrl record`, `fastrl replay`, `fastrl assist`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from . import SetOpt, SpecArg, app, err, exit_with, out

RunOpt = Annotated[
    Path | None,
    typer.Option(
        "--assist", metavar="RUN_DIR", help="a trained run: path suggestions (Enter) and its value as the cue"
    ),
]


def _no_display(e: Exception) -> None:
    """Exit 2 with a hint when no window can be opened."""
    err.print(
        f"cannot open the viewer window ({e}); on a machine without a screen run under "
        "`xvfb-run -a -s '-screen 0 1280x800x24'` with MUJOCO_GL=egl",
        markup=False,
    )
    raise typer.Exit(code=2)


@app.command()
def record(
    spec: SpecArg,
    subject: Annotated[str, typer.Option("--subject", help="who is recorded (saved in the trajectory)")],
    output: Annotated[Path, typer.Option("-o", "--output", metavar="DIR", help="folder for the attempts")] = Path(
        "recordings"
    ),
    assist: RunOpt = None,
    seed: Annotated[int, typer.Option(help="task seed (avatar jitter, start pose)")] = 0,
    overrides: SetOpt = None,
    linger: Annotated[
        float, typer.Option(help="seconds the feedback stays on screen (negative: until the window is closed)")
    ] = -1.0,
    suggest_every: Annotated[float | None, typer.Option(help="also suggest a path every this many seconds")] = None,
    feedback: Annotated[bool, typer.Option(help="score the attempt when it ends")] = True,
) -> None:
    """Drive the scope in the MuJoCo viewer with the keyboard; each attempt is saved as a trajectory."""
    from ..spec import SpecError, load_spec
    from ..teleop.record import record as run_record

    try:
        task_spec = load_spec(spec, overrides or ())
        result = run_record(
            task_spec,
            subject,
            output,
            assist,
            seed,
            linger=linger,
            feedback=feedback,
            suggest_every=suggest_every,
            say=lambda m: err.print(m, markup=False),
        )
    except (SpecError, FileNotFoundError, ValueError) as e:
        exit_with(e)
    except Exception as e:  # GLFW / mujoco.FatalError without a display
        if "GLFW" in str(e) or "display" in str(e).lower():
            _no_display(e)
        raise
    t = result["timing"]
    out.print(f"saved {escape(str(result['path']))} ({result['end']})")
    if "period_ms_mean" in t:
        out.print(
            f"control loop: {t['period_ms_mean']:.1f} ms mean period (target {t['control_period_ms']:.0f}), "
            f"{t['work_ms_mean']:.1f} ms work, {t['late_ticks']} late ticks"
        )
    if "rrd" in result:
        out.print(f"rerun: {escape(str(result['rrd']))}")


@app.command()
def replay(
    file: Annotated[Path, typer.Argument(metavar="FILE", help="a recorded trajectory (.npz)", show_default=False)],
    spec: Annotated[Path | None, typer.Option("--spec", help="the spec, if the file does not carry it")] = None,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Rerun recording (default FILE.replay.rrd)")
    ] = None,
    viewer: Annotated[bool, typer.Option(help="play it in the MuJoCo viewer too")] = True,
    speed: Annotated[float, typer.Option(help="playback speed in the viewer")] = 1.0,
) -> None:
    """Play a recorded trajectory back in the viewer and into a Rerun recording."""
    from ..data.trajectory import Trajectory, TrajectoryError
    from ..spec import SpecError
    from ..teleop.offline import attempt_recording, replay_in_viewer, spec_of_trajectory
    from ..teleop.record import markdown_feedback

    try:
        traj = Trajectory.load(file)
        task_spec = spec_of_trajectory(traj, spec)
        fb = traj.meta.get("feedback")
        rrd = attempt_recording(
            task_spec,
            traj,
            output or file.with_suffix(".replay.rrd"),
            feedback_md=markdown_feedback(fb) if fb else None,
        )
    except (SpecError, TrajectoryError, FileNotFoundError, ValueError) as e:
        exit_with(named(file, e))
    out.print(f"rerun: {escape(str(rrd))}")
    if viewer:
        try:
            n = replay_in_viewer(task_spec, traj, speed)
        except Exception as e:
            if "GLFW" in str(e) or "display" in str(e).lower():
                _no_display(e)
            raise
        out.print(f"played {n} of {len(traj.time)} samples")


@app.command("assist")
def assist_cmd(
    run: Annotated[Path, typer.Argument(metavar="RUN_DIR", help="a trained run (networks/)", show_default=False)],
    file: Annotated[Path, typer.Argument(metavar="TRAJ", help="a recorded trajectory (.npz)", show_default=False)],
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="Rerun recording (default TRAJ.assist.rrd)")
    ] = None,
    every: Annotated[float, typer.Option(help="seconds between suggestions")] = 1.0,
) -> None:
    """Assist a recorded attempt offline: suggestions at regular points and the value along the way, in Rerun."""
    from ..assess.scoring import foreign_problem
    from ..data.trajectory import Trajectory, TrajectoryError
    from ..spec import SpecError
    from ..teleop.offline import attempt_recording, spec_of_run, spec_of_trajectory
    from ..teleop.record import markdown_feedback

    try:
        traj = Trajectory.load(file)
        task_spec = spec_of_trajectory(traj) if "task_spec" in traj.meta else spec_of_run(run)
        problem = foreign_problem(traj, task_spec)
        if problem:
            raise TrajectoryError(f"{file}: {problem}")
        fb = traj.meta.get("feedback")
        text = markdown_feedback(fb) if fb else None
        rrd = attempt_recording(
            task_spec, traj, output or file.with_suffix(".assist.rrd"), run, every_s=every, feedback_md=text
        )
    except (SpecError, TrajectoryError, FileNotFoundError, ValueError) as e:
        exit_with(named(file, e))
    out.print(f"rerun: {escape(str(rrd))}")


def named(file: Path, error: Exception) -> Exception:
    """A trajectory problem with the file named in front (as in batches); other errors as they are."""
    from ..data.trajectory import TrajectoryError

    if isinstance(error, TrajectoryError) and not str(error).startswith(str(file)):
        return TrajectoryError(f"{file}: {error}")
    return error
