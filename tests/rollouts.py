"""Seeded rollouts of the bundled specs (expert and random actions): the references of unchanged behaviour."""

from __future__ import annotations

import hashlib

import numpy as np

import fastrl
from fastrl.agents.expert import ScriptedExpert, run_expert_episode
from fastrl.model import compile_task

from .conftest import spec_file

REFERENCE_SPECS = ("imagecentring", "periscoping", "tracelines", "liver_tour")
REFERENCE_MODES = ("discrete", "continuous", "rates")
EXPERT_STEPS, RANDOM_STEPS = 200, 100


def rollout(env, policy: str, seed: int, steps: int) -> dict[str, np.ndarray]:
    """Observations, rewards and portal coordinates of one seeded episode prefix."""
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    expert = ScriptedExpert(env) if policy == "expert" else None
    out = {"obs": [obs], "reward": [], "portal": [env.unwrapped.portal_coordinates()]}
    for _ in range(steps):
        action = expert.act(obs) if expert else env.action_space.sample()
        obs, r, term, trunc, _ = env.step(action)
        out["obs"].append(obs)
        out["reward"].append(r)
        out["portal"].append(env.unwrapped.portal_coordinates())
        if term or trunc:
            break
    return {k: np.asarray(v, np.float64) for k, v in out.items()}


def references(name: str, spec=None) -> dict[str, np.ndarray]:
    """Every rollout of one spec (by name, or a given TaskSpec of it) keyed 'name/mode/policy/array'."""
    out = {}
    for mode in REFERENCE_MODES:
        env = fastrl.make(spec if spec is not None else spec_file(name), actions={"mode": mode})
        for policy, steps in (("expert", EXPERT_STEPS), ("random", RANDOM_STEPS)):
            for key, arr in rollout(env, policy, seed=3, steps=steps).items():
                out[f"{name}/{mode}/{policy}/{key}"] = arr
        env.close()
    return out


def expert_episodes(name: str, spec=None) -> np.ndarray:
    """(return, steps, subtasks) of whole scripted-expert episodes on seeds 0 and 1, in the spec's own mode."""
    env = fastrl.make(spec if spec is not None else spec_file(name))
    rows = []
    for seed in (0, 1):
        r = run_expert_episode(env, seed=seed)
        rows.append([r["return"], r["steps"], r["subtasks"]])
    env.close()
    return np.array(rows, np.float64)


def model_digest(spec) -> str:
    """SHA-256 of the compiled MJCF of a spec path or TaskSpec."""
    from fastrl.spec import load_spec

    task_spec = spec if not hasattr(spec, "suffix") else load_spec(spec)
    return hashlib.sha256(compile_task(task_spec).xml.encode()).hexdigest()
