"""Evaluation with sampled actions: reproducible, not the greedy episodes, training's randomness untouched."""

import torch

from fastrl.agents.sb3 import build_model, make_vec_env, policy_function
from fastrl.env import FastEnv
from fastrl.runner.train.evaluate import evaluate
from fastrl.spec import load_spec

from ..conftest import spec_file

SEEDS = [10_000, 10_001]


def test_sampled_evaluation_repeats_itself_differs_from_greedy_and_leaves_torch_alone():
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=3", "train.workers=1", "train.n_envs=1"])
    assert load_spec(spec_file("tracelines_pixels")).evaluate.sampling_seed == 10_000
    assert spec.evaluate.sampling_seed is None  # the kinematic specs evaluate greedily
    venv = make_vec_env(spec, 1, 0)
    model = build_model(spec, venv, seed=0)  # untrained: its sampled actions are far from its most likely ones

    def episodes(sampling_seed):
        summary, _ = evaluate(FastEnv(spec), policy_function(model, venv, sampling_seed), SEEDS)
        return [(e["return"], e["steps"]) for e in summary["per_episode"]]

    torch.manual_seed(7)
    expected = torch.rand(3)
    torch.manual_seed(7)
    first = episodes(10_000)
    assert torch.equal(torch.rand(3), expected)  # its draws were its own
    assert episodes(10_000) == first
    assert episodes(10_001) != first and episodes(None) != first


def test_evaluation_actions_are_sb3_predicts_and_leave_the_policy_in_evaluation_mode():
    for overrides in ([], ["train.algo=SAC", "actions.mode=rates"]):
        spec = load_spec(spec_file("tracelines"), ["train.workers=1", "train.n_envs=2", *overrides])
        venv = make_vec_env(spec, 2, 0)
        model = build_model(spec, venv, seed=0)
        obs = venv.reset()
        for _ in range(3):
            obs = venv.step(venv.action_space.sample()[None].repeat(2, 0))[0]
        model.policy.set_training_mode(True)  # as an update leaves it, mid-training
        fast = policy_function(model, venv)
        for o in obs:
            expected = model.predict(venv.normalize_obs(o[None]), deterministic=True)[0][0]
            assert str(fast(o)) == str(expected if expected.ndim else int(expected))
        assert not model.policy.training
        venv.close()
