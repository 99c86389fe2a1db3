"""Synthetic trainee cohorts: trajectories of graded skill levels, and their figures by level."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from ..env.fast_env import FastEnv
from ..spec.models import TaskSpec
from .families import draw_mix, foreign_family, mixed_profile, overlay_severities
from .instruments_trainee import TwoInstrumentTrainee
from .overlays import overlaid
from .replay import replay_arrays, rollout_trajectory
from .trainee import Trainee
from .trajectory import Trajectory


def subject_name(level: int, index: int) -> str:
    """A subject's name: level and 1-based index within the level, e.g. L2-S07."""
    return f"L{level}-S{index:02d}"


def make_cohort(
    spec: TaskSpec,
    levels: int,
    per_level: int,
    seed: int = 0,
    env: FastEnv | None = None,
    families: tuple[str, ...] = ("classic",),
) -> Iterator[Trajectory]:
    """Yield per_level trajectories for each level 1..levels (seeds seed, seed+1, ... in that order); each subject
    mixes the deficit `families` in shares of its own (fastrl.data.families), the level setting their total."""
    if per_level < 1:
        raise ValueError(f"per_level must be at least 1, got {per_level}")
    env = env or FastEnv(spec)
    problem = foreign_family(families, bool(env.task.instruments))
    if problem:
        raise ValueError(problem)
    for level in range(1, levels + 1):
        for i in range(per_level):
            s = seed + (level - 1) * per_level + i
            mix = draw_mix(families, s)
            profile = mixed_profile(mix, level, levels)
            trainee = (TwoInstrumentTrainee if env.task.instruments else Trainee)(env, profile, s)
            meta = {
                "source": "synthetic",
                "subject": subject_name(level, i + 1),
                "skill": level,
                "levels": levels,
                "families": mix,
                "profile": profile.as_dict(),
            }
            traj = rollout_trajectory(env, trainee.act, s, meta, trainee.reset)[0]
            severities = overlay_severities(mix, level, levels)
            yield with_overlays(env, traj, severities, s) if severities else traj


def with_overlays(env: FastEnv, traj: Trajectory, severities: dict[str, float], seed: int) -> Trajectory:
    """The trajectory's scope motion deformed by kinematic overlays, on the control grid, without its actions (they
    no longer match); ValueError for a task with instruments or loose bodies (overlays deform the scope alone)."""
    if traj.instruments is not None or traj.bodies is not None:
        raise ValueError("kinematic overlay families deform the scope alone: not for this task")
    hz = env.task_spec.episode.control_hz
    portal = overlaid(traj.portal, severities, seed, hz, env.task.ranges)
    meta = {**traj.meta, "overlays": severities}
    return Trajectory(traj.time[0] + np.arange(len(portal)) / hz, portal, meta)


def replayed_figures(env, traj: Trajectory) -> dict:
    """Heuristic return, subtasks done and duration of a trajectory, recomputed by replay."""
    done = replay_arrays(env, traj)
    duration = (len(done.rewards) - 1) * env.unwrapped.dt  # the env's clock at the last sample replayed
    return {"return": float(done.rewards.sum()), "subtasks": int(done.subtasks), "duration": duration}


def level_table(rows: list[dict]) -> list[dict]:
    """Mean and sd of each figure by skill level, from rows with `skill`, `return`, `subtasks`, `duration`."""
    table = []
    for level in sorted({r["skill"] for r in rows}):
        group = [r for r in rows if r["skill"] == level]
        entry = {"skill": level, "n": len(group)}
        for key in ("return", "subtasks", "duration"):
            values = np.array([r[key] for r in group], float)
            entry[key] = float(values.mean())
            entry[f"{key}_sd"] = float(values.std(ddof=1)) if len(values) > 1 else 0.0
        table.append(entry)
    return table
