"""The lean SAC update computes stable-baselines3's SAC update, and the spec chooses between them."""

import copy

import numpy as np
import pytest
import torch
from stable_baselines3 import SAC

from fastrl.agents.lean_sac import LeanSAC, squashed_sample
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.runner.train.monitoring import periodic_every
from fastrl.spec import load_spec

from ..conftest import spec_file

SETS = [
    "actions.mode=rates",
    "train.algo=SAC",
    "train.n_envs=1",
    "train.sac.learning_starts=200",
    "train.sac.net_arch=[32, 32]",
    "train.sac.batch_size=64",
]


def sac_pair():
    """An SB3 SAC after a few hundred steps, and a LeanSAC with its weights, buffer and temperature."""
    spec = load_spec(spec_file("tracelines"), [*SETS, "train.sac.lean_update=false"])
    venv = make_vec_env(spec, 1, 0)
    plain = build_model(spec, venv)
    plain.learn(260)
    lean = build_model(load_spec(spec_file("tracelines"), SETS), venv)
    assert type(plain) is SAC and type(lean) is LeanSAC
    for m in (plain, lean):  # plain SGD: Adam would magnify float rounding in near-zero gradients
        m.actor.optimizer = torch.optim.SGD(m.actor.parameters(), lr=0.05)
        m.critic.optimizer = torch.optim.SGD(m.critic.parameters(), lr=0.05)
        m.ent_coef_optimizer = torch.optim.SGD([m.log_ent_coef], lr=0.05)
    lean.policy.load_state_dict(plain.policy.state_dict())
    lean.log_ent_coef.data[:] = plain.log_ent_coef.data
    lean.replay_buffer, lean._logger = plain.replay_buffer, plain._logger
    return plain, lean


def train_seeded(model, steps: int) -> None:
    """Gradient steps with fixed numpy (replay sampling) and torch (actions) generators."""
    np.random.seed(7)
    torch.manual_seed(7)
    model.train(gradient_steps=steps, batch_size=64)


def test_lean_update_equals_sb3_update():
    plain, lean = sac_pair()
    before, updates = copy.deepcopy(plain.policy.state_dict()), (plain._n_updates, lean._n_updates)
    for m in (plain, lean):
        train_seeded(m, 4)
    a, b = plain.policy.state_dict(), lean.policy.state_dict()
    moved = max((a[k] - before[k]).abs().max().item() for k in a)
    assert moved > 1e-3  # the updates did something, in actor, critic and target
    for prefix in ("actor.", "critic.", "critic_target."):
        assert any((a[k] - before[k]).abs().max() > 0 for k in a if k.startswith(prefix)), prefix
    for k in a:
        assert torch.allclose(a[k], b[k], atol=1e-6), k
    assert torch.allclose(plain.log_ent_coef, lean.log_ent_coef, atol=1e-7)
    assert (plain._n_updates - updates[0], lean._n_updates - updates[1]) == (4, 4)


def test_squashed_sample_matches_sb3_distribution():
    from stable_baselines3.common.distributions import SquashedDiagGaussianDistribution

    mean, log_std = torch.randn(50, 3), torch.randn(50, 3).clamp(-2, 1)
    torch.manual_seed(3)
    action, log_prob = squashed_sample(mean, log_std)
    torch.manual_seed(3)
    ref_action, ref_log_prob = SquashedDiagGaussianDistribution(3).log_prob_from_params(mean, log_std)
    assert torch.allclose(action, ref_action, atol=1e-6)
    assert torch.allclose(log_prob, ref_log_prob, atol=1e-4)


@pytest.mark.parametrize("lean, cls", [(True, LeanSAC), (False, SAC)])
def test_spec_chooses_the_update(lean, cls):
    spec = load_spec(spec_file("tracelines"), [*SETS, f"train.sac.lean_update={str(lean).lower()}"])
    assert type(build_model(spec, make_vec_env(spec, 1, 0))) is cls


@pytest.mark.parametrize("algo, cadence", [("PPO", 50_000), ("SAC", 10_000)])
def test_sac_evaluates_on_its_own_cadence_and_sb3_never_sees_it(algo, cadence):
    sets = ["train.algo=SAC", "actions.mode=rates"] if algo == "SAC" else []
    cadences = ["evaluate.periodic_every=50000", "train.sac.periodic_every=10000"]
    spec = load_spec(spec_file("tracelines"), [*sets, *cadences])
    assert periodic_every(spec) == cadence
    assert "periodic_every" not in spec.train.sb3_params()
    plain = load_spec(spec_file("tracelines"), [*sets, "train.sac.periodic_every=null"])
    assert periodic_every(plain) == plain.evaluate.periodic_every
