"""Off-policy adversarial IRL on SAC: current-rollout sampling, relabelling on sampling, spectral norm switch."""

import numpy as np
import pytest
import torch

import fastrl
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.data.replay import expert_trajectories
from fastrl.irl import (
    Discriminator,
    DiscriminatorFit,
    DiscriminatorForm,
    OffPolicyAdversarialCallback,
    RelabelingReplayBuffer,
)
from fastrl.irl.demonstrations import expert_transitions
from fastrl.irl.discriminator import augment
from fastrl.spec import load_spec

from ..conftest import spec_file

TINY = [
    "actions.mode=continuous",
    "train.algo=SAC",
    "train.n_envs=2",
    "train.sac.learning_starts=64",
    "train.sac.batch_size=32",
    "train.sac.train_freq=8",
    "train.sac.gradient_steps=2",
    "train.sac.buffer_size=1000",
    "train.sac.net_arch=[32, 32]",
    "episode.time_limit=4",
    "irl.algorithm=airl",
]


@pytest.fixture(scope="module")
def setup():
    """A tiny SAC generator with the relabelling buffer and two continuous expert demonstrations."""
    spec = load_spec(spec_file("tracelines"), TINY)
    return spec, expert_transitions(fastrl.make(spec), expert_trajectories(fastrl.make(spec), range(2)))


def train(spec, expert, current_rollout: bool, spectral: bool = False, steps: int = 240, every: int = 0):
    """SAC with the off-policy adversarial callback for a few hundred steps, counting discriminator fits."""
    venv = make_vec_env(spec, 2, 0)
    model = build_model(spec, venv, replay_buffer_class=RelabelingReplayBuffer)
    disc = Discriminator(
        venv.observation_space.shape[0], DiscriminatorForm(kind="airl", gamma=0.99, hidden=(32, 32), spectral=spectral)
    )
    cb = OffPolicyAdversarialCallback(
        DiscriminatorFit(disc, batch_size=32), expert, current_rollout=current_rollout, steps=2, every=every
    )
    fit, cb.fits = cb.fit.steps, []
    cb.fit.steps = lambda policy, exp, n: cb.fits.append(model.num_timesteps) or fit(policy, exp, n)
    model.learn(steps, callback=cb)
    return model, disc, cb


def test_current_rollout_sampling_draws_only_from_the_latest_rollout(setup):
    spec, expert = setup
    model, disc, cb = train(spec, expert, current_rollout=True)
    buf = model.replay_buffer
    pos, env_idx = cb.last_policy_rows
    steps = model.train_freq.frequency  # 8 steps of each of the 2 envs
    assert sorted(set(pos.tolist())) == [(buf.pos - k) % buf.buffer_size for k in range(steps, 0, -1)]
    assert sorted(set(env_idx.tolist())) == [0, 1] and len(pos) == steps * buf.n_envs
    _, _, cb_all = train(spec, expert, current_rollout=False)
    pos_all, _ = cb_all.last_policy_rows
    assert len(set(pos_all.tolist())) > steps  # the ablation samples the whole buffer


def test_fitting_every_k_steps_uses_everything_since_the_last_fit(setup):
    spec, expert = setup
    model, _, cb = train(spec, expert, current_rollout=True)
    assert cb.fits == list(range(64, 241, 16))  # after every rollout of 8 steps x 2 envs, past learning_starts
    model, _, cb = train(spec, expert, current_rollout=True, every=64)
    assert cb.fits == [64, 128, 192]
    buf = model.replay_buffer
    pos, env_idx = cb.last_policy_rows  # the 64 transitions collected between the fits at 128 and 192
    assert len(pos) == 64 and sorted(set(env_idx.tolist())) == [0, 1]
    assert sorted(set(pos.tolist())) == [(buf.pos - 24 - k) % buf.buffer_size for k in range(32, 0, -1)]


def test_sampled_rewards_are_relabelled_by_the_current_discriminator(setup):
    spec, expert = setup
    model, disc, cb = train(spec, expert, current_rollout=True)
    assert {"irl/disc_loss", "irl/disc_accuracy", "irl/reward_expert"} <= set(cb.stats)
    buf = model.replay_buffer
    samples = buf.sample(64, env=model.get_vec_normalize_env())
    with torch.no_grad():
        s, s2 = augment(samples.observations), augment(samples.next_observations)
        done = samples.dones.reshape(-1)
        expected = disc.f(s, s2, done) + done * 0.99 * disc.absorbing_value()
    np.testing.assert_allclose(samples.rewards.reshape(-1).numpy(), expected.numpy(), rtol=1e-5, atol=1e-5)
    assert not np.allclose(samples.rewards.numpy(), 0.0)
    assert samples.discounts is None or samples.discounts.shape == samples.rewards.shape


def test_spectral_norm_switch_reaches_the_discriminator(setup):
    spec, expert = setup
    _, disc, _ = train(spec, expert, current_rollout=True, spectral=True, steps=128)
    linear = [m for m in disc.modules() if isinstance(m, torch.nn.Linear)]
    assert linear and all(torch.nn.utils.parametrize.is_parametrized(m, "weight") for m in linear)
    assert max(torch.linalg.matrix_norm(m.weight, 2).item() for m in linear) <= 1.05
