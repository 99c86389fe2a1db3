"""What `fastrl run`, `fastrl irl` and `fastrl eval` print: the evaluation table, stops, advice, where a run is."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.markup import escape

from ..spec import SpecError
from . import err, exit_with, out, write_text


def train_and_report(
    spec: Path | None, overrides: list[str], resume: Path | None, runs: Path, progress: bool, timesteps: int | None
) -> None:
    """Start (or resume) a run or study, turn interruptions and bad input into messages, print the evaluation."""
    from ..agents.checkpoint_files import CheckpointDamaged, CheckpointMismatch
    from ..atomic import DiskFull
    from ..forked import deferred
    from ..runner.runs.runfiles import RunFileError, read_eval
    from ..runner.runs.stops import EvaluationInterrupted, RunInterrupted, RunOutOfSpace, stop_on_sigterm
    from ..runner.train.training import expert_started, plan_training, train
    from .stops import report_stop

    expert = None
    with stop_on_sigterm(until_exit=True):  # a second Ctrl-C while the run saves is ignored until exit
        try:
            plan = plan_training(spec, overrides, resume)
            if plan.study:
                from .study import study_and_report

                return study_and_report(plan, runs, progress)
            with deferred():  # kept in `expert` before a stop can land
                expert = expert_started(plan)
            run_dir = train(plan, runs, out, progress, timesteps, expert=expert)
        except (RunInterrupted, EvaluationInterrupted, RunOutOfSpace, DiskFull) as stop:
            report_stop(stop)
        except (SpecError, FileNotFoundError, CheckpointMismatch, CheckpointDamaged, RunFileError) as e:
            exit_with(e)
        finally:
            if expert is not None:
                expert.cancel()
    print_eval(read_eval(run_dir))
    from ..runner.train.advice import learning_advice

    advice = learning_advice(run_dir, spec)
    if advice:
        err.print(f"warning: {advice}", markup=False, style="yellow")
    out.print(f"run saved in {escape(str(run_dir))}; view it with: fastrl view {escape(str(run_dir))}")


def eval_and_report(run_dir: Path | None, expert: Path | None, episodes: int | None, output: Path | None) -> None:
    """Re-evaluate a saved run or the scripted expert, print the figures (and write them to `output`)."""
    from ..runner import EvaluationInterrupted, evaluate_expert, evaluate_saved
    from ..runner.runs.stops import stop_on_sigterm
    from .runcheck import check_run
    from .stops import stop_code

    if (run_dir is None) == (expert is None):
        err.print("give RUN_DIR, or --expert SPEC", markup=False)
        raise typer.Exit(code=2)
    if run_dir is not None:
        check_run(run_dir, {"spec.yaml"})
    with stop_on_sigterm(until_exit=True):
        try:
            results = evaluate_saved(run_dir, episodes) if run_dir else evaluate_expert(expert, (), episodes)
        except EvaluationInterrupted as stop:
            err.print(f"{stop.signal_name}: evaluation stopped; nothing was written", markup=False)
            err.print(f"evaluate again with: fastrl eval {stop.run}", markup=False)
            raise typer.Exit(code=stop_code(stop.signal_name)) from None
        except (SpecError, FileNotFoundError) as e:
            exit_with(e)
    print_eval(results)
    if output is not None:
        write_text(output, json.dumps(results, indent=2))


def print_eval(results: dict) -> None:
    """A table of evaluation figures, agent next to expert."""
    from rich.table import Table

    table = Table(title=f"evaluation over {len(results['seeds'])} episodes")
    table.add_column("policy")
    for col in ("success", "subtasks", "return", "time (s)", "path (m)"):
        table.add_column(col, justify="right")
    for who in ("agent", "expert"):
        r = results.get(who)
        if r:
            table.add_row(
                who,
                f"{r['success_rate']:.0%}",
                f"{r['subtasks_completed']:.1%}",
                f"{r['return_mean']:.1f}",
                f"{r['episode_time_mean']:.1f}",
                f"{r['path_length_mean']:.3f}",
            )
    out.print(table)
