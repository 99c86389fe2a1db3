"""`fastrl assess --seeds N --address ADDR`: each seed's scorer learned as a Ray task, two to each of the cluster's
CPUs at once; the run folders must be the same paths on every node (as for `fastrl score --address`)."""

from __future__ import annotations

import time
from pathlib import Path

from rich.console import Console

from .runs.rundir import latest_checkpoint
from .runs.stops import RunInterrupted
from .seeds_at_once import CPUS_PER_SEED, SEEDS_PER_CORE, learn_one


def learn_on_ray(address: str, spec_path: Path, runs: list[tuple[list[str], Path]], console: Console) -> list[Path]:
    """Learn each (overrides, folder) of `runs` as a Ray task at `address` ("local": a Ray on this machine); the
    folders in order. A failed seed stops the others and is raised as a ValueError naming it; Ctrl-C stops them all
    (each saves its checkpoint and recording) and raises a RunInterrupted for the first unfinished one."""
    import ray

    from .score.ray_scoring import connect

    connected = connect(address)
    try:
        cpus = CPUS_PER_SEED / SEEDS_PER_CORE  # two seeds to a CPU, as on this machine's cores
        task = ray.remote(num_cpus=cpus, max_retries=0)(learn_one)
        pending = {task.remote(str(spec_path), o, str(into)): into for o, into in runs}
        t0 = time.perf_counter()
        console.print(f"learning {len(runs)} seeds on Ray ({address}), {cpus:g} CPU each", highlight=False)
        try:
            while pending:
                ready, _ = ray.wait(list(pending), num_returns=1)
                into = pending.pop(ready[0])
                _result(ray, ready[0], into)
                console.print(f"learned {into.name} in {time.perf_counter() - t0:.0f} s", highlight=False)
        except KeyboardInterrupt:
            raise _stopped(ray, pending) from None
        except ValueError:
            for ref in pending:
                ray.cancel(ref, force=True)
            raise
        return [into for _, into in runs]
    finally:
        if connected:
            ray.shutdown()


def _result(ray, ref, into: Path) -> None:
    """Wait for one seed's task; a failure as a ValueError naming its folder and cause."""
    try:
        ray.get(ref)
    except ray.exceptions.RayTaskError as e:
        cause = e.cause if getattr(e, "cause", None) is not None else e
        raise ValueError(f"learning {into} on Ray failed: {type(cause).__name__}: {cause}") from None
    except ray.exceptions.RayError as e:  # a worker or node lost
        raise ValueError(f"learning {into} on Ray failed: {type(e).__name__}: {e}") from None


def _stopped(ray, pending: dict) -> Exception:
    """Ctrl-C: interrupt every unfinished seed (inside the task as a Ctrl-C: it saves its checkpoint and recording
    and stops); a RunInterrupted for the first, at its newest checkpoint, or a KeyboardInterrupt if none was made."""
    for ref in pending:
        ray.cancel(ref)
    ray.wait(list(pending), num_returns=len(pending), timeout=60)
    for into in pending.values():
        checkpoint = latest_checkpoint(into)
        if checkpoint is not None:
            return RunInterrupted(into, int(checkpoint.name))
    return KeyboardInterrupt()
