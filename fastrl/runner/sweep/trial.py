"""The Ray Tune trainable of a sweep: one trial, an ordinary run in its directory under the sweep folder."""

from __future__ import annotations

import io
import json
import os
import shutil
import socket
import time
from datetime import UTC, datetime
from pathlib import Path

from rich.console import Console

from ..runs.rundir import latest_checkpoint
from ..runs.runfiles import read_eval
from .plan import is_finished, trial_overrides


def run_trial(config: dict) -> None:
    """Ray Tune trainable: one ordinary run into its directory (resumed from a checkpoint, skipped if finished)."""
    import ray
    import torch
    from ray import tune

    from ..train.run import resume_run, start_run

    cpus = int(config["cpus"])
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(cpus)
    torch.set_num_threads(cpus)
    trial, run = config["trial"], Path(config["sweep"]) / config["trial"]["name"]
    with (Path(config["sweep"]) / "attempts.log").open("a") as log:
        log.write(f"{trial['name']} {datetime.now(UTC).isoformat(timespec='seconds')}\n")
    node = ray.get_runtime_context().get_node_id()
    t0 = time.perf_counter()
    if not is_finished(run):
        quiet = Console(file=io.StringIO())
        if latest_checkpoint(run) is not None:
            resume_run(run, quiet, progress=False)
        else:
            if run.is_dir():  # a failed or interrupted attempt that left no checkpoint
                shutil.rmtree(run)
            overrides = [*trial_overrides(trial), f"train.workers={cpus}"]  # no env processes beyond its CPUs
            start_run(Path(config["sweep"]) / "spec.yaml", overrides, console=quiet, progress=False, into=run)
        info = {"trial": trial, "node_id": node, "host": socket.gethostname(), "pid": os.getpid()}
        info |= {"wall_s": time.perf_counter() - t0, "torch_threads": torch.get_num_threads()}
        (run / "trial.json").write_text(json.dumps(info, indent=2))
    agent = read_eval(run)["agent"]
    tune.report(
        {
            "success": agent["success_rate"],
            "subtasks": agent["subtasks_completed"],
            "return": agent["return_mean"],
            "node_id": json.loads((run / "trial.json").read_text())["node_id"],
        }
    )
