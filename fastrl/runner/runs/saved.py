"""Load what a finished (or interrupted) run saved: its spec and policy."""

from __future__ import annotations

import warnings
from pathlib import Path

from ...agents.sb3 import build_model, checkpoint_problem, load_checkpoint, make_vec_env, policy_function
from ...spec.models import TaskSpec
from .rundir import latest_checkpoint
from .runfiles import read_run_spec


def load_policy(run: Path) -> tuple[TaskSpec, object]:
    """A saved run's spec and its final (or newest) policy as obs -> action."""
    run = Path(run)
    spec = read_run_spec(run)
    weights = run / "final" if checkpoint_problem(run / "final") is None else latest_checkpoint(run)
    if weights is None:
        raise FileNotFoundError(f"{run} has no saved policy")
    return spec, checkpoint_policy(spec, weights)


def checkpoint_policy(spec: TaskSpec, checkpoint: Path):
    """The policy (obs -> action) saved in one checkpoint directory, acting as the spec evaluates it."""
    venv = make_vec_env(spec, 1, spec.train.seed)
    with warnings.catch_warnings():  # SB3 warns that one env cannot fill a training batch: we only act
        warnings.simplefilter("ignore", UserWarning)
        model = build_model(spec, venv)
    load_checkpoint(checkpoint, model, venv)
    venv.training = False
    return policy_function(model, venv, spec.evaluate.sampling_seed)
