"""LeanActorCriticPolicy: the rollout call gives SB3's actions, values and log probabilities bit for bit."""

import pytest
import torch
from stable_baselines3.common.policies import ActorCriticPolicy

from fastrl.agents.critic_columns import ColumnCriticPolicy
from fastrl.agents.lean_policy import LeanActorCriticPolicy
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.spec import load_spec

from ..conftest import spec_file

GENERATOR = ["irl.algorithm=airl", "irl.generator.ppo.n_steps=16", "irl.generator.ppo.batch_size=32"]


@pytest.mark.parametrize(
    "overrides, cls",
    [
        ([], LeanActorCriticPolicy),
        (["train.ppo.activation=relu"], LeanActorCriticPolicy),
        ([*GENERATOR, "irl.generator.value_ignore=[tip_pos, portal]"], ColumnCriticPolicy),
    ],
)
def test_the_lean_rollout_call_equals_sb3s(overrides, cls):
    spec = load_spec(spec_file("tracelines"), overrides)
    venv = make_vec_env(spec, 4, 0)
    model = build_model(spec, venv)
    policy = model.policy
    assert type(policy) is cls and policy.lean
    obs = torch.randn(64, venv.observation_space.shape[0]) * 3
    with torch.no_grad():
        for deterministic in (False, True):
            torch.manual_seed(5)
            lean = [policy(obs, deterministic) for _ in range(3)]
            torch.manual_seed(5)
            plain = [ActorCriticPolicy.forward(policy, obs, deterministic) for _ in range(3)]
            for a, b in zip(lean, plain, strict=True):
                for x, y in zip(a, b, strict=True):
                    assert x.shape == y.shape and x.dtype == y.dtype
                    assert torch.equal(x, y)
            assert len({tuple(a[0].tolist()) for a in lean}) == (1 if deterministic else 3)  # sampling did sample
    venv.close()


def test_continuous_actions_keep_sb3s_call():
    spec = load_spec(spec_file("tracelines"), ["actions.mode=rates"])
    venv = make_vec_env(spec, 2, 0)
    policy = build_model(spec, venv).policy
    assert isinstance(policy, LeanActorCriticPolicy) and not policy.lean
    actions, values, log_prob = policy(torch.zeros(2, venv.observation_space.shape[0]))
    assert actions.shape == (2, *venv.action_space.shape) and values.shape == (2, 1) and log_prob.shape == (2,)
    venv.close()
