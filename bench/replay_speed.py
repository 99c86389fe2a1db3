"""How fast scoring replays a recording: by columns and step by step, beside the kinematics alone, in one run.

    python bench/replay_speed.py                                   # a 5 x 20 cohort of each task, made here
    python bench/replay_speed.py --tasks tracelines --cohort DIR   # a cohort of recordings on disk

For each task, every recording is replayed as scoring replays it (held still to the time limit), step by step
(`data.replay.replay`) and by columns (`env.column_replay.replay_columns`), interleaved over --rounds; the two must
agree bit for bit (observations, rewards, tips, subtasks), else the bench stops. The reference is the physics
floor: `mj_fwdPosition` alone at each sample replayed. Prints microseconds per replayed sample (median of the
rounds) with the machine and its load.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
from common import load_after, machine_line

from fastrl.assess.scoring import held_to_limit
from fastrl.data import load_trajectories
from fastrl.data.cohort import make_cohort
from fastrl.data.replay import replay
from fastrl.env.column_replay import can_replay_columns, replay_columns
from fastrl.env.fast_env import FastEnv
from fastrl.spec import load_spec

SPECS = Path(__file__).resolve().parent.parent / "specs"


def recordings(spec, env, cohort: Path | None) -> list:
    """The cohort's recordings (made here: 5 levels x 20), each held still to the limit as scoring holds it."""
    if cohort is not None:
        trajs = [t for _, t in load_trajectories(cohort)[0]]
    else:
        trajs = list(make_cohort(spec, 5, 20, env=env))
    return [held_to_limit(t, spec, len(t.time)) or t for t in trajs]


def stepwise(env, traj) -> tuple:
    """Observations, rewards, tips and subtasks, step by step."""
    tips = []
    obs, infos, rewards = replay(env, traj, lambda u: tips.append(u.state.tip_pos))
    return obs, rewards, np.array(tips), infos[-1]["subtask"]


def by_columns(env, traj) -> tuple:
    """The same, by columns."""
    r = replay_columns(env, traj.portal, int(traj.meta.get("seed", 0)))
    return r.observations, r.rewards, r.tips, r.subtasks


def kinematics(env, traj, n: int) -> None:
    """mj_fwdPosition at the first n samples: the floor under any replay."""
    u = env.unwrapped
    m, d, qadr = u.model, u.data, u.task.qadr
    for q in traj.portal[:n]:
        d.qpos[qadr] = q
        mujoco.mj_fwdPosition(m, d)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="+", default=["tracelines", "imagecentring", "periscoping"])
    parser.add_argument("--cohort", type=Path, help="recordings of the (single) task instead of a cohort made here")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print(f"# {machine_line()}")
    for task in args.tasks:
        spec = load_spec(SPECS / f"{task}.yaml")
        env = FastEnv(spec)
        if not can_replay_columns(env):
            print(f"{task}: replays step by step (no array form of every term)")
            continue
        trajs = recordings(spec, env, args.cohort)
        lengths = []
        for traj in trajs:  # each must agree bit for bit; the lengths replayed set the floor's samples
            a, b = stepwise(env, traj), by_columns(env, traj)
            if not all(np.array_equal(x, y) for x, y in zip(a, b)):
                sys.exit(f"{task}: the two replays differ on {traj.meta.get('subject')}")
            lengths.append(len(a[1]))
        samples = sum(lengths)
        times = {"step by step": [], "by columns": [], "mj_fwdPosition alone": []}
        for _ in range(args.rounds):
            for name, fn in (("step by step", stepwise), ("by columns", by_columns)):
                t0 = time.perf_counter()
                for traj in trajs:
                    fn(env, traj)
                times[name].append((time.perf_counter() - t0) / samples * 1e6)
            t0 = time.perf_counter()
            for traj, n in zip(trajs, lengths):
                kinematics(env, traj, n)
            times["mj_fwdPosition alone"].append((time.perf_counter() - t0) / samples * 1e6)
        med = {k: statistics.median(v) for k, v in times.items()}
        print(f"{task}: {len(trajs)} recordings, {samples} samples replayed, equal bit for bit")
        for name, us in med.items():
            print(f"  {name:<22} {us:6.1f} us a sample  (rounds: {', '.join(f'{x:.1f}' for x in times[name])})")
        print(f"  by columns: {med['step by step'] / med['by columns']:.1f}x step by step, "
              f"{med['by columns'] / med['mj_fwdPosition alone']:.1f}x the kinematics alone")  # fmt: skip
    print(load_after())


if __name__ == "__main__":
    main()
