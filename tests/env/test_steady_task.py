"""A seventh task family is one module (env/steady_task.py), one spec (fixtures/steady.yaml) and these tests."""

from pathlib import Path

from gymnasium.utils.env_checker import check_env

from fastrl.agents.expert import run_expert_episode
from fastrl.env import FastEnv
from fastrl.spec import load_spec

from .steady_task import SteadyTask

SPEC = Path(__file__).parents[1] / "fixtures" / "steady.yaml"
HOLD = 0  # the discrete no-op: the scope stays where it is


def test_held_still_the_steady_episode_ends_after_its_seconds():
    env = FastEnv(load_spec(SPEC), family=SteadyTask)
    env.reset(seed=0)
    for _ in range(200):
        _, _, terminated, truncated, info = env.step(HOLD)
        if terminated or truncated:
            break
    assert terminated and not info["success"] and 1.5 <= info["time"] <= 2.0  # the servos settle first


def test_the_expert_keeps_moving_and_completes_the_steady_task():
    env = FastEnv(load_spec(SPEC), family=SteadyTask)
    assert all(run_expert_episode(env, seed=seed)["success"] for seed in (0, 1))


def test_the_steady_env_passes_the_gymnasium_checker():
    check_env(FastEnv(load_spec(SPEC), family=SteadyTask), skip_render_check=True)
