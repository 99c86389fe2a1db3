"""Demonstrations: trajectories of the scripted expert or of a trained run, written in the contract."""

from __future__ import annotations

from pathlib import Path

from rich.progress import Progress

from ..agents.expert import ScriptedExpert
from ..data.replay import rollout_trajectory
from ..env.fast_env import FastEnv
from ..spec import load_spec
from ..spec.models import TaskSpec
from .saved import load_policy


def write_demos(
    out: Path,
    n: int,
    seed: int = 0,
    run: Path | None = None,
    expert_spec: Path | TaskSpec | None = None,
    overrides=(),
    progress: bool = True,
) -> list[Path]:
    """Write n trajectories (seeds seed..seed+n-1) from a run's policy or the scripted expert (spec or its file)."""
    if run is not None:
        spec, policy = load_policy(run)
        env, on_reset, meta = FastEnv(spec), None, {"source": "agent", "subject": Path(run).name}
    else:
        spec = expert_spec if isinstance(expert_spec, TaskSpec) else load_spec(expert_spec, overrides)
        env = FastEnv(spec)
        expert = ScriptedExpert(env)
        policy, on_reset, meta = expert.act, expert.reset, {"source": "expert", "subject": "scripted-expert"}
    out = Path(out)
    paths = []
    with Progress(disable=not progress) as bar:
        task = bar.add_task(f"demonstrations of {spec.name}", total=n)
        for i in range(n):
            traj, _ = rollout_trajectory(env, policy, seed + i, meta, on_reset)
            paths.append(traj.save(out / f"{spec.name}-{meta['source']}-s{seed + i:05d}.npz"))
            bar.advance(task)
    return paths
