"""Demonstrations: trajectories of the scripted expert or of a trained run, written in the contract."""

from __future__ import annotations

from pathlib import Path

from rich.progress import Progress

from ...agents.expert import ScriptedExpert
from ...data.render_video import write_trajectory_video
from ...data.replay import rollout_trajectory
from ...data.video_import import endoscope_size
from ...env.fast_env import FastEnv
from ...spec import load_spec
from ...spec.models import TaskSpec
from ..runs.saved import load_policy


def write_demos(
    out: Path,
    n: int,
    seed: int = 0,
    run: Path | None = None,
    expert_spec: Path | TaskSpec | None = None,
    overrides=(),
    progress: bool = True,
    video: bool = False,
) -> list[Path]:
    """Write n trajectories (seeds seed..seed+n-1) from a run's policy or the scripted expert (spec or its file);
    `video`: each one's endoscope video beside it (.mp4, the spec's evaluate.image_size, the control rate)."""
    if run is not None:
        spec, policy = load_policy(run)
        env, on_reset, meta = FastEnv(spec, **_size(spec)), None, {"source": "agent", "subject": Path(run).name}
    else:
        spec = expert_spec if isinstance(expert_spec, TaskSpec) else load_spec(expert_spec, overrides)
        env = FastEnv(spec, **_size(spec))
        expert = ScriptedExpert(env)
        policy, on_reset, meta = expert.act, expert.reset, {"source": "expert", "subject": "scripted-expert"}
    out = Path(out)
    paths = []
    with Progress(disable=not progress) as bar:
        task = bar.add_task(f"demonstrations of {spec.name}", total=n)
        for i in range(n):
            traj, _ = rollout_trajectory(env, policy, seed + i, meta, on_reset)
            paths.append(traj.save(out / f"{spec.name}-{meta['source']}-s{seed + i:05d}.npz"))
            if video:
                write_trajectory_video(env, traj, paths[-1].with_suffix(".mp4"))
            bar.advance(task)
    return paths


def _size(spec: TaskSpec) -> dict:
    """The env's render size: the task's endoscope images (evaluate.image_size)."""
    w, h = endoscope_size(spec)
    return {"width": w, "height": h}
