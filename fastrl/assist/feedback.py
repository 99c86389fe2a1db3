"""Feedback after an attempt: scores, standing against the expert, and the moments of largest deviation."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..assess.figures import deviations
from ..assess.references import expert_paths, reference_scores
from ..assess.scoring import Scorer, normalise
from ..data.replay import replay_arrays, rollout_trajectory
from ..data.trajectory import Trajectory


def worst_moments(dev_mm: np.ndarray, duration: float, k: int = 3, apart: int = 10) -> list[dict]:
    """The k largest deviations (by percent of the procedure), at least `apart` percent from each other."""
    chosen: list[int] = []
    for i in np.argsort(-dev_mm):
        if all(abs(int(i) - j) >= apart for j in chosen):
            chosen.append(int(i))
        if len(chosen) == k:
            break
    n = len(dev_mm) - 1
    return [
        {
            "percent": i * 100 // max(n, 1),
            "time_s": round(duration * i / max(n, 1), 2),
            "deviation_mm": round(float(dev_mm[i]), 1),
        }
        for i in sorted(chosen)
    ]


def attempt_feedback(
    scorer: Scorer, traj: Trajectory, cache: Path | None = None, references: int = 2, policy=None
) -> dict:
    """Scores of one attempt, normalised against random (0) and the scripted expert (1), and where it deviated.

    With `policy` (a trained agent, batch obs -> actions) the agent's own episode from the same seed is scored too.
    """
    refs = reference_scores(scorer, references, cache)
    scored = scorer.score(traj, "attempt")
    normalise([scored], refs)
    out = {
        "scores": scored.scores,
        "normalised": scored.normalised,
        "expert": refs["expert"],
        "success": scored.meta["success"],
        "subtasks_done": scored.meta["subtasks_done"],
        "subtasks_total": scored.meta["subtasks_total"],
    }
    nets = scorer.networks
    if nets is not None and not scorer.learned:  # forward RL: a value but no learned reward
        values = nets.value(replay_arrays(scorer.env, traj).observations).astype(float)
        out["scores"]["value_mean"] = float(values.mean())
    if policy is not None:
        agent, _ = rollout_trajectory(
            scorer.env,
            lambda o: policy(o[None])[0],
            traj.seed,
            {"source": "agent", "subject": "trained agent"},
        )
        out["agent"] = scorer.score(agent, "agent").scores
    dev = deviations([scored], expert_paths(scorer, [traj.seed])).get("attempt")
    out["deviation_mm"] = [] if dev is None else [round(float(v), 2) for v in dev]
    out["worst_moments"] = [] if dev is None else worst_moments(dev, float(scored.time[-1]))
    return out


def feedback_text(fb: dict) -> str:
    """What the trainee reads after an attempt."""
    s, n, e = fb["scores"], fb["normalised"], fb["expert"]
    lines = [
        f"{'DONE' if fb['success'] else 'ended'}: {fb['subtasks_done']} of {fb['subtasks_total']} subtasks",
        f"time {s['time']:.1f} s (expert {e['time']:.1f} s)",
        f"path length {100 * s['path_length']:.1f} cm (expert {100 * e['path_length']:.1f} cm)",
        f"smoothness {s['smoothness']:.2f} (expert {e['smoothness']:.2f}; higher is smoother)",
        f"heuristic {s['heuristic']:.2f} = {_pct(n.get('heuristic'))} of the expert's",
    ]
    if s.get("reward") is not None:
        lines.append(f"learned reward {s['reward']:.2f} = {_pct(n.get('reward'))} of the expert's")
    if s.get("value") is not None:
        lines.append(f"learned value gain {s['value']:.2f} = {_pct(n.get('value'))} of the expert's")
    if s.get("value_mean") is not None:
        lines.append(f"mean learned value {s['value_mean']:.2f}")
    if fb.get("agent"):
        a = fb["agent"]
        lines.append(
            f"trained agent from the same start: {100 * a['subtasks']:.0f}% of subtasks in {a['time']:.1f} s, "
            f"{100 * a['path_length']:.1f} cm, heuristic {a['heuristic']:.2f}"
        )
    if fb["worst_moments"]:
        lines.append("largest deviations from the expert's path:")
        lines += [
            f"  at {m['percent']}% ({m['time_s']:.1f} s): {m['deviation_mm']:.0f} mm" for m in fb["worst_moments"]
        ]
    return "\n".join(lines)


def _pct(x) -> str:
    """A normalised score as a percentage (expert = 100%)."""
    return "-" if x is None else f"{100 * x:.0f}%"
