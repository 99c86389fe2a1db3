"""Which steps should the motion's likelihood read? The shipped camera speed and turn rate against more of the pose.

    python bench/motion_features.py --tasks periscoping
    python bench/motion_features.py --tasks periscoping tracelines imagecentring --json docs/motion_features.json
    python bench/motion_features.py --tasks tracelines --families classic jitter --kinds pumping
    python bench/motion_features.py --tasks tracelines --sets speed speed+view     # where the camera points too

The learned scores add the motion's log-likelihood under the density of the best K's steps (fastrl.assess.motion:
each step's camera speed and turn rate and how much each changed). Deficits the speed and turn rate do not separate
(pumping in and out along the shaft, a rolling horizon) might read better from the motion split along the scope's
axes; deficits of where the camera points (depth, horizon, field of view) from a density of the view beside the
motion's. No training: each cohort (bench/validity.py's families, bench/outside_cohorts.py's kinds) is replayed once,
and for each set of step features the protocol's `--by motion` rule is run with that set (best 10 by the stopwatch,
the density of their steps, the best 10 by the sum of the ranks by duration and by likelihood, the density of
theirs); printed: the mean level of that best 10 and the Kendall tau-b of every recording's likelihood under their
density against the levels, per cohort and as means over the families and over the outside kinds. Writes --json.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import time
from pathlib import Path

import numpy as np
from common import machine_line


def changed(m: np.ndarray) -> np.ndarray:
    """The magnitudes and how much each changed since the step before (none at the first)."""
    return np.column_stack([m, np.abs(m - np.concatenate([m[:1], m[:-1]]))])


def camera_axes(obs: np.ndarray, at: dict) -> np.ndarray:
    """Each step's speed along the camera's view axis and across it, its roll rate about that axis and its pointing
    rate (the angular velocity across it): (n, 4)."""
    v, (w, x, y, z), qd = obs[:, at["tip_vel"]], obs[:, at["tip_quat"]].T, obs[:, at["tip_quat_rate"]]
    fwd = -np.column_stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])  # the frame's -z
    a, b, c, d = qd.T  # world angular velocity: the vector part of 2 dq/dt q*
    omega = 2 * np.column_stack(
        [-a * x + b * w - c * z + d * y, -a * y + b * z + c * w - d * x, -a * z - b * y + c * x + d * w]
    )
    along, turn = (v * fwd).sum(1), (omega * fwd).sum(1)
    across = np.linalg.norm(v - along[:, None] * fwd, axis=1)
    return np.column_stack([np.abs(along), across, np.abs(turn), np.linalg.norm(omega - turn[:, None] * fwd, axis=1)])


def portal_rates(obs: np.ndarray, at: dict, hz: float) -> np.ndarray:
    """Each step's pivoting rate (pitch and yaw), insertion rate, shaft roll rate and light cable rate, in the
    observation's scaled portal coordinates: (n, 4)."""
    p = obs[:, at["portal"]]
    d = np.concatenate([np.zeros((1, p.shape[1])), np.diff(p, axis=0)]) * hz
    return np.column_stack([np.linalg.norm(d[:, :2], axis=1), np.abs(d[:, 2]), np.abs(d[:, 3]), np.abs(d[:, 4])])


def view(obs: np.ndarray, at: dict) -> np.ndarray:
    """Where each step's camera points: its distance to the avatar, the avatar's angle off the view's centre and the
    horizon's tilt against the avatar's up (rad): (n, 3)."""
    distance = np.linalg.norm(obs[:, at["target_pos"]] - obs[:, at["tip_pos"]], axis=1)
    x, y, z = obs[:, at["target_in_camera"]].T
    sine, cosine = obs[:, at["horizon_error"]].T
    return np.column_stack([distance, np.arctan2(np.hypot(x, y), z), np.abs(np.arctan2(sine, cosine))])


def speed_steps(obs: np.ndarray, at: dict) -> np.ndarray:
    """The shipped step features: the camera's speed and turn rate, each with its change since the step before."""
    from fastrl.assess.motion import step_motion

    return step_motion(obs, (at["tip_vel"], at["tip_quat_rate"]))


SETS = {  # each set's step features, as the groups whose densities multiply (one group: one joint density)
    "speed": lambda o, at, hz: [speed_steps(o, at)],  # shipped
    "camera": lambda o, at, hz: [changed(camera_axes(o, at))],
    "portal": lambda o, at, hz: [changed(portal_rates(o, at, hz))],
    "speed+shaft": lambda o, at, hz: [speed_steps(o, at), changed(camera_axes(o, at)[:, [0, 2]])],
    "view": lambda o, at, hz: [view(o, at)],
    "speed+view": lambda o, at, hz: [speed_steps(o, at), view(o, at)],
    "speed+distance": lambda o, at, hz: [speed_steps(o, at), view(o, at)[:, :1]],
}


def likelihoods(steps: list[list[np.ndarray]], own: list[int], fitted: list[int]) -> np.ndarray:
    """Every recording's log-likelihood under the density of the `fitted` recordings' own steps (group by group)."""
    from fastrl.assess.motion import MotionModel

    total = np.zeros(len(steps))
    for g in range(len(steps[0])):
        model = MotionModel.fit([steps[i][g][: own[i]] for i in fitted])
        total += [model.log_likelihood(s[g]) for s in steps]
    return total


def cohort_rows(task: str, folder: Path, top: int, sets: list[str]) -> dict:
    """The `--by motion` rule's best `top` and the motion's tau-b under each feature set, for one cohort."""
    from scipy.stats import kendalltau, rankdata

    from fastrl.assess.scoring import Scorer
    from fastrl.data.inverse import to_control_rate
    from fastrl.data.trajectory import Trajectory
    from fastrl.spec import load_spec
    from fastrl.spec.columns import column_terms

    spec = load_spec(f"specs/{task}.yaml")
    names, scorer, hz = column_terms(spec), Scorer(spec), spec.episode.control_hz
    at = {n: [i for i, m in enumerate(names) if m == n] for n in dict.fromkeys(names)}
    rows = []
    for path in sorted(folder.glob("*.npz")):
        traj = to_control_rate(Trajectory.load(path), hz)
        scored, obs = scorer.replayed(traj, path.stem)
        features = {name: SETS[name](obs, at, hz) for name in sets}
        rows.append((path.stem, int(traj.meta["skill"]), len(traj.time), scored.scores, features))
    level, own = np.array([r[1] for r in rows]), [r[2] for r in rows]
    done, took = [r[3]["subtasks"] for r in rows], [r[3]["time"] for r in rows]
    by_time = sorted(range(len(rows)), key=lambda i: (-done[i], took[i], rows[i][0]))[:top]
    out = {}
    for name in rows[0][4]:
        steps = [r[4][name] for r in rows]
        both = rankdata(took) + rankdata(-likelihoods(steps, own, by_time))
        best = sorted(range(len(rows)), key=lambda i: (-done[i], both[i], rows[i][0]))[:top]
        tau = kendalltau(likelihoods(steps, own, best), level).statistic
        out[name] = {"level": float(level[best].mean()), "motion": float(tau)}
    return out


def main() -> None:
    import outside_cohorts
    import validity

    from fastrl.data.families import FAMILIES

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="+", default=["periscoping"], choices=outside_cohorts.SCOPE_ONLY)
    parser.add_argument("--families", nargs="+", default=[*FAMILIES, "mixed"])
    parser.add_argument("--kinds", nargs="+", default=[*outside_cohorts.KINDS, "mix"])
    parser.add_argument("--sets", nargs="+", default=list(SETS), choices=list(SETS), help="the feature sets compared")
    parser.add_argument("--top", type=int, default=10)
    parser.add_argument("--root", type=Path, default=Path("runs"), help="holds bench-validity/ and bench-outside/")
    parser.add_argument("--json", type=Path, default=Path("docs/motion_features.json"))
    args = parser.parse_args()
    started = {"machine": machine_line(), "utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime())}
    print(f"# {started['utc']} UTC, {started['machine']}", flush=True)
    print(f"per feature set: mean level of the `--by motion` best {args.top}, the motion's tau-b", flush=True)
    rows = []
    for task in args.tasks:
        made = [("family", f, validity.cohort(task, f, args.root / "bench-validity")) for f in args.families]
        made += [("outside", k, outside_cohorts.cohort(task, k, args.root / "bench-outside")) for k in args.kinds]
        for group, name, folder in made:
            rows.append(
                {"task": task, "group": group, "cohort": name, "sets": cohort_rows(task, folder, args.top, args.sets)}
            )
            cells = "  ".join(f"{s} {v['level']:.1f} {v['motion']:+.2f}" for s, v in rows[-1]["sets"].items())
            print(f"{task:13s} {name:14s} {cells}", flush=True)
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({**started, "rows": rows}, indent=1))  # kept as it goes
        for group in ("family", "outside"):
            mine = [r["sets"] for r in rows if r["task"] == task and r["group"] == group]
            if mine:
                means = {s: [np.mean([m[s][k] for m in mine]) for k in ("level", "motion")] for s in mine[0]}
                cells = "  ".join(f"{s} {lv:.2f} {tau:.3f}" for s, (lv, tau) in means.items())
                print(f"{task:13s} {group + f' ({len(mine)})':14s} {cells}", flush=True)
    print(f"# ended {time.strftime('%H:%M', time.gmtime())} UTC, {machine_line()}")


if __name__ == "__main__":
    main()
