"""Adversarial IRL on PPO: rewards are relabelled, AIRL's r_psi is separable, spectral norm bounds layers."""

import numpy as np
import pytest
import torch

import fastrl
from fastrl.agents.expert import ScriptedExpert
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.data.replay import expert_transitions, rollout_trajectory
from fastrl.irl import AdversarialCallback, Discriminator
from fastrl.spec import load_spec

from .conftest import spec_file

TINY = ["train.normalize.reward=false", "train.n_envs=2", "train.ppo.n_steps=64", "train.ppo.batch_size=64",
        "train.ppo.n_epochs=1", "episode.time_limit=8"]


@pytest.fixture(scope="module")
def expert_data():
    """Expert transitions of two TraceLines demonstrations."""
    spec = load_spec(spec_file("tracelines"), TINY)
    env = fastrl.make(spec)
    expert = ScriptedExpert(env)
    trajs = [rollout_trajectory(env, expert.act, s, {"source": "expert"}, expert.reset)[0] for s in range(2)]
    return spec, expert_transitions(fastrl.make(spec), trajs)


@pytest.mark.parametrize("kind", ["gail", "airl"])
def test_rollout_rewards_are_replaced_by_the_discriminator(expert_data, kind):
    spec, expert = expert_data
    assert expert.terminal[-1] == 1.0 and len(expert.obs) == len(expert.actions)
    venv = make_vec_env(spec, 2, 0)
    model = build_model(spec, venv)
    disc = Discriminator(venv.observation_space.shape[0], kind, 0.99)
    cb = AdversarialCallback(disc, expert, epochs=1, batch_size=64)
    before = [p.detach().clone() for p in disc.parameters()]
    model.learn(256, callback=cb)
    assert any(not torch.equal(a, b) for a, b in zip(before, disc.parameters()))
    assert {"irl/disc_loss", "irl/disc_accuracy", "irl/learned_reward_policy"} <= set(cb.stats)
    buf = model.rollout_buffer
    env_rewards = np.stack(cb.env_rewards)
    assert not np.allclose(buf.rewards, env_rewards)


def test_airl_reward_is_separable_from_the_shaping():
    disc = Discriminator(6, "airl", 0.9)
    s, s2 = torch.randn(32, 6), torch.randn(32, 6)
    term, log_pi = torch.zeros(32), torch.zeros(32)
    r, f = disc.reward(s).detach().clone(), disc.f(s, s2, term).detach().clone()
    with torch.no_grad():
        for p in disc.h.parameters():
            p.add_(1.0)
    assert torch.allclose(disc.reward(s), r)
    assert not torch.allclose(disc.f(s, s2, term), f)
    with torch.no_grad():
        expected = disc.reward(s) + 0.9 * disc.h(s2).squeeze(-1) - disc.h(s).squeeze(-1)
    assert torch.allclose(disc.f(s, s2, term), expected)
    assert torch.allclose(disc.f(s, s2, torch.ones(32)), disc.reward(s) - disc.h(s).squeeze(-1))
    assert torch.allclose(disc.logits(s, s2, term, log_pi + 1.0), disc.logits(s, s2, term, log_pi) - 1.0)
    with pytest.raises(ValueError):
        Discriminator(6, "gail", 0.9).reward(s)


def layer_norms_after_training(spectral: bool) -> list[float]:
    """Largest singular value of each linear layer after pushing the logits up for 50 steps."""
    torch.manual_seed(0)
    disc = Discriminator(8, "gail", 0.99, hidden=(32, 32), spectral=spectral)
    optim = torch.optim.Adam(disc.parameters(), lr=1e-2)
    x = torch.randn(256, 8) * 5
    for _ in range(50):
        loss = -disc.logits(x, x, torch.zeros(256), torch.zeros(256)).abs().mean()
        optim.zero_grad()
        loss.backward()
        optim.step()
    with torch.no_grad():  # let the power iteration settle on the final weights
        for _ in range(10):
            disc.logits(x, x, torch.zeros(256), torch.zeros(256))
    disc.eval()
    return [torch.linalg.matrix_norm(m.weight, 2).item() for m in disc.modules() if isinstance(m, torch.nn.Linear)]


def test_spectral_norm_bounds_every_layer():
    bounded, free = layer_norms_after_training(True), layer_norms_after_training(False)
    assert len(bounded) == 3 and max(bounded) <= 1.05
    assert max(free) > 1.5  # the same training without it grows the layers
