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
