"""Scaling the generator's learned reward by the running spread of its discounted return."""

import numpy as np
import pytest

import fastrl
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.data.replay import expert_trajectories
from fastrl.irl import AdversarialCallback, Discriminator, DiscriminatorFit, DiscriminatorForm
from fastrl.irl.demonstrations import expert_transitions
from fastrl.irl.scaling import ReturnScale
from fastrl.spec import load_spec

from ..conftest import spec_file
from .test_irl_history import TINY


def stream(steps=500, envs=3, seed=0):
    """Rewards and episode ends of a made-up rollout."""
    rng = np.random.default_rng(seed)
    return rng.normal(2.0, 1.0, (steps, envs)).astype(np.float32), rng.random((steps, envs)) < 0.02


def test_the_scale_is_the_spread_of_the_discounted_returns_and_ignores_the_rewards_unit():
    rewards, dones = stream()
    scale = ReturnScale(3, gamma=0.9, clip=1e9)
    scaled = scale(rewards, dones)
    ret, returns = np.zeros(3), []
    for r, d in zip(rewards, dones):  # the discounted return of each env, restarted after an episode ends
        ret = ret * 0.9 + r
        returns.append(ret.copy())
        ret[d] = 0.0
    assert np.isclose(np.sqrt(scale.stats.var), np.std(returns), rtol=1e-3)
    np.testing.assert_allclose(scaled, rewards / np.std(returns), rtol=1e-3)
    np.testing.assert_allclose(ReturnScale(3, gamma=0.9, clip=1e9)(rewards * 1000, dones), scaled, rtol=1e-4)
    assert np.abs(ReturnScale(3, gamma=0.9, clip=0.1)(rewards, dones)).max() <= 0.1 + 1e-7


def test_the_generator_gets_the_scaled_learned_reward(monkeypatch):
    spec = load_spec(spec_file("tracelines"), TINY)
    expert = expert_transitions(fastrl.make(spec), expert_trajectories(fastrl.make(spec), range(2)))
    venv = make_vec_env(spec, 2, 0)
    model = build_model(spec, venv)
    cb = AdversarialCallback(
        DiscriminatorFit(
            Discriminator(venv.observation_space.shape[0], DiscriminatorForm(kind="airl", gamma=0.99)), batch_size=64
        ),
        expert,
        epochs=1,
        scale_reward=True,
    )
    seen = []
    real_scale = ReturnScale.__call__

    def spy(self, rewards, dones):
        out = real_scale(self, rewards, dones)
        seen.append((rewards.copy(), out.copy()))
        return out

    monkeypatch.setattr(ReturnScale, "__call__", spy)
    model.learn(256, callback=cb)
    assert len(seen) == 2 and cb.scale.stats.count > 256  # both rollouts, every step of both envs
    raw, scaled = seen[-1]
    spread = cb.stats["irl/generator_reward_scale"]
    assert spread > 0 and not np.isclose(spread, 1.0)
    np.testing.assert_allclose(scaled, np.clip(raw / spread, -10, 10), rtol=1e-4)
    buf, ended = model.rollout_buffer.rewards, np.stack(cb.dones)  # SB3 adds gamma V(s_T) where an episode is cut
    assert ended.any() and buf.shape == scaled.shape
    np.testing.assert_allclose(buf[~ended], scaled[~ended], rtol=1e-5)


@pytest.mark.parametrize(
    ("algorithm", "setting", "expected"),
    [("airl", None, True), ("gail", None, False), ("airl", False, False), ("gail", True, True)],
)
def test_scaling_defaults_on_for_airl_and_off_for_gail(tmp_path, algorithm, setting, expected):
    from rich.console import Console

    from fastrl.runner.train.learner import build_learner

    value = "null" if setting is None else str(setting).lower()  # null: the default (the FAST specs set true)
    sets = [
        *TINY,
        f"irl.algorithm={algorithm}",
        "irl.demonstrations.expert=1",
        f"irl.discriminator.scale_reward={value}",
    ]
    learner = build_learner(load_spec(spec_file("tracelines"), sets), tmp_path, Console(quiet=True), progress=False)
    assert learner.callbacks[0].scale_reward is expected
