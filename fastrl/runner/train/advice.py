"""After a run: one plain warning when the agent is far below the scripted expert, and what to try."""

from __future__ import annotations

from pathlib import Path

from ...bundled import SPECS_DIR, find_spec
from ...spec import SpecError, load_spec
from ..runs.runfiles import read_eval, read_meta

FAR_BELOW = 0.5  # the agent completes under half the expert's share of subtasks


def bundled_spec(kind: str) -> Path | None:
    """The bundled spec of a task kind (e.g. specs/tracelines.yaml for trace_lines), if there is one."""
    for path in sorted(SPECS_DIR.glob("*.yaml")):
        try:
            if load_spec(path).task.kind == kind:
                return path
        except SpecError:
            continue
    return None


def learning_advice(run: Path, spec_path: Path | None = None) -> str | None:
    """A warning if the run's agent is far below the expert on the same seeds, or None.

    `spec_path` is the spec file the run started from: its own train.timesteps (before --timesteps
    or --set) is the budget to suggest. Without it (a resumed run) the run's spec.yaml stands in.
    """
    ev = read_eval(run)
    agent, expert = ev.get("agent"), ev.get("expert")
    if not agent or not expert:
        return None
    done, reference = agent["subtasks_completed"], expert["subtasks_completed"]
    if reference <= 0 or done >= FAR_BELOW * reference:
        return None
    spec = load_spec(run / "spec.yaml")
    trained = read_meta(run).get("trained_timesteps") or spec.train.timesteps
    budget = load_spec(spec_path).train.timesteps if spec_path is not None else spec.train.timesteps
    tips = []
    if trained < budget:
        tips.append(f"train to the spec's budget, --timesteps {budget}")
    tuned = bundled_spec(spec.task.kind)
    if tuned is not None and (spec_path is None or find_spec(spec_path).resolve() != tuned.resolve()):
        tips.append(
            f"compare the train: and reward: sections with {tuned}, "
            f"tuned to learn in {load_spec(tuned).train.timesteps:,} timesteps"
        )
    if not tips:
        tips.append(f"train longer, e.g. --timesteps {2 * trained}")
    return (
        f"after {trained:,} timesteps the agent completes {done:.0%} of the subtasks, the scripted expert "
        f"{reference:.0%}: it has not learned the task yet. Try: " + "; or ".join(tips) + "."
    )
