"""`fastrl assess --seeds N` on a machine with spare cores: the seeds' scorers learned in processes of their own, up to
two per core at once; the same runs, folder for folder, as one after another (RESULTS: seeds learned at once)."""

from __future__ import annotations

import io
import os
import signal
import time
from concurrent.futures import FIRST_COMPLETED, Future, wait
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from ..env.render import rendered_here
from ..forked import Worker, outcome
from .runs.rundir import latest_checkpoint
from .runs.stops import EvaluationInterrupted, RunInterrupted, shielded, signal_name, stop_on_sigterm

CPUS_PER_SEED = 1  # a seed's threads, and no env process beside it: its second process added little
# a seed learning alone leaves part of its core idle: on 2 cores, 3 seeds at once took 103 s, 2 at a time 158 s
SEEDS_PER_CORE = 2
STOP_WAIT_S, RESEND_S = 120.0, 2.0  # how long a stop waits for the seeds to save, and how often it asks again


def at_once(seeds: int) -> int:
    """How many seeds learn at once on this machine: up to two per core; one after another on one core, or once this
    process rendered (a frame estimator learned for videos: Mesa's EGL would deadlock a forked child)."""
    cores = os.cpu_count() or 1
    return 1 if cores < 2 or rendered_here() else min(seeds, SEEDS_PER_CORE * cores)


def learn_one(spec_path: str, overrides: list[str], into: str) -> str | None:
    """One seed's learning run into its folder (or its resumption there), quiet, on one core's threads; its path, or
    None if it was stopped."""
    import torch

    from .train.run import learn_into

    os.environ["OMP_NUM_THREADS"] = str(CPUS_PER_SEED)
    torch.set_num_threads(CPUS_PER_SEED)
    quiet = Console(file=io.StringIO())
    try:  # on one process: the split never changes results
        done = learn_into(Path(spec_path), overrides, Path(into), console=quiet, progress=False, workers=CPUS_PER_SEED)
        return str(done)
    except (RunInterrupted, EvaluationInterrupted):  # saved already; the parent names where to resume
        return None


def learn_at_once(
    spec_path: Path, runs: list[tuple[list[str], Path]], console: Console, processes: int, progress: bool = True
) -> list[Path]:
    """Learn each (overrides, folder) of `runs`, `processes` at a time, each in its own process; the folders in
    order. A failed seed stops the others and is raised as a ValueError naming it; Ctrl-C or SIGTERM stops them all
    (each saves its checkpoint and recording) and raises a RunInterrupted for the first unfinished one."""
    workers = [Worker(orphan_exit=True) for _ in range(processes)]
    queue, running = list(runs), {}  # running: future -> (worker, folder)
    t0 = time.perf_counter()
    console.print(f"learning {len(runs)} seeds, {processes} at once, each in its own process", highlight=False)
    bar = Progress(
        TextColumn("seeds learned"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        console=console,
        disable=not progress,
        transient=True,
    )

    def feed(worker: Worker) -> None:
        """Start the next seed waiting, if any, on `worker`."""
        if queue:
            overrides, into = queue.pop(0)
            running[worker.submit(learn_one, str(spec_path), overrides, str(into))] = (worker, into)

    with stop_on_sigterm():
        try:
            with bar:
                task = bar.add_task("seeds", total=len(runs))
                for worker in workers:
                    feed(worker)
                while running:
                    done, _ = wait(list(running), return_when=FIRST_COMPLETED)
                    for future in done:
                        worker, into = running.pop(future)
                        if _learned(future, into) is None:  # stopped on its own (SIGTERM to it alone)
                            raise KeyboardInterrupt
                        console.print(f"learned {into.name} in {time.perf_counter() - t0:.0f} s", highlight=False)
                        bar.advance(task)
                        feed(worker)
            return [into for _, into in runs]
        except KeyboardInterrupt as stop:
            with shielded():  # a second Ctrl-C cannot cut the seeds' saving short
                raise _stopped(running, [into for _, into in runs], signal_name(stop)) from None
        finally:
            for worker in workers:
                worker.kill()


def _learned(future: Future, into: Path) -> str | None:
    """A finished seed's folder (None if it was stopped); a failure as a ValueError naming its folder and cause."""
    try:
        return outcome(future, f"the seed learning into {into}")
    except Exception as e:  # ChildFailed too: its process died
        raise ValueError(f"learning {into} failed: {type(e).__name__}: {e}") from None


def _stopped(running: dict[Future, tuple[Worker, Path]], order: list[Path], how: str) -> Exception:
    """Stop every unfinished seed (SIGTERM: it saves its checkpoint and recording, then ends its run) and wait for
    them; a RunInterrupted (by `how`, SIGINT or SIGTERM) for the first in `order`, at its newest checkpoint, or a
    KeyboardInterrupt if none was made."""
    deadline = time.monotonic() + STOP_WAIT_S
    while (left := [f for f in running if not f.done()]) and time.monotonic() < deadline:
        for future in left:  # again every few seconds: a stop that came during a fork is lost (fastrl.forked)
            process = running[future][0].process
            if process is not None and process.is_alive():
                os.kill(process.pid, signal.SIGTERM)  # a seed already saving ignores it
        wait(left, timeout=RESEND_S)
    unfinished = {into for _, into in running.values()}
    for into in (f for f in order if f in unfinished):
        checkpoint = latest_checkpoint(into)
        if checkpoint is not None:
            return RunInterrupted(into, int(checkpoint.name), how)
    return KeyboardInterrupt()
