"""A seventh task family is one module (env/gentle_task.py), one spec (fixtures/gentle.yaml) and these tests."""

from pathlib import Path

from gymnasium.utils.env_checker import check_env

from fastrl.agents.expert import run_expert_episode
from fastrl.env import FastEnv
from fastrl.env.dome_task import DomeTask
from fastrl.spec import load_spec

from .gentle_task import GentleTask

SPEC = Path(__file__).parents[1] / "fixtures" / "gentle.yaml"
INSERT = 5  # the discrete action that pushes the scope in: from the start pose it runs into the plate


def test_the_expert_never_touches_so_both_families_run_it_alike():
    spec = load_spec(SPEC)
    dome, gentle = FastEnv(spec), FastEnv(spec, family=GentleTask)
    assert type(dome.family) is DomeTask and type(gentle.family) is GentleTask
    for seed in (0, 1):
        done = run_expert_episode(dome, seed=seed)
        assert run_expert_episode(gentle, seed=seed) == done and done["success"]


def test_the_first_touch_ends_a_gentle_episode_and_only_a_gentle_one():
    spec = load_spec(SPEC)
    for family, ends in ((None, False), (GentleTask, True)):
        env = FastEnv(spec, family=family)
        env.reset(seed=0)
        for _ in range(200):
            _, _, terminated, truncated, info = env.step(INSERT)
            if info["contacts"] or terminated or truncated:
                break
        assert info["contacts"] >= 1 and terminated is ends and not truncated and not info["success"]


def test_the_gentle_env_passes_the_gymnasium_checker():
    check_env(FastEnv(load_spec(SPEC), family=GentleTask), skip_render_check=True)
