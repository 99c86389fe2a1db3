"""irl.generator.value_ignore: the generator's critic (the learned value) reads only the other columns."""

import numpy as np
import torch

from fastrl.agents.critic_columns import ColumnCriticPolicy
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.irl.export import load_networks, save_networks
from fastrl.spec import load_spec
from fastrl.spec.columns import columns_without, value_inputs

from ..conftest import spec_file

IGNORED = ["tip_pos", "portal"]
TINY = [
    "irl.algorithm=airl",
    "irl.generator.ppo.n_steps=16",
    "irl.generator.ppo.batch_size=32",
    f"irl.generator.value_ignore=[{', '.join(IGNORED)}]",
]


def test_the_critic_ignores_its_columns_the_actor_does_not_and_the_export_agrees(tmp_path):
    spec = load_spec(spec_file("tracelines"), TINY)
    venv = make_vec_env(spec, 2, 0)
    model = build_model(spec, venv)
    assert isinstance(model.policy, ColumnCriticPolicy) and value_inputs(spec) == columns_without(spec, IGNORED)
    select = model.policy.mlp_extractor.value_net[0].weight.detach().clone()
    model.learn(200)
    assert torch.equal(model.policy.mlp_extractor.value_net[0].weight, select)  # the selection never trains
    ignored = sorted(set(range(select.shape[1])) - set(value_inputs(spec)))
    assert len(ignored) == 3 + 5 and torch.equal(select.sum(0)[ignored], torch.zeros(len(ignored)))
    x = torch.as_tensor(venv.normalize_obs(np.asarray(venv.get_original_obs(), np.float32)))
    moved = x.clone()
    moved[:, ignored] += 1.0
    with torch.no_grad():
        v, v_moved = model.policy.predict_values(x), model.policy.predict_values(moved)
        logits = model.policy.get_distribution(x).distribution.logits
        logits_moved = model.policy.get_distribution(moved).distribution.logits
    assert torch.equal(v, v_moved) and not torch.allclose(logits, logits_moved)  # the actor still sees them
    kept = x.clone()
    kept[:, value_inputs(spec)[0]] += 1.0
    with torch.no_grad():
        assert not torch.allclose(model.policy.predict_values(kept), v)
    save_networks(tmp_path, model, venv, None, 0.9)
    raw = np.asarray(venv.get_original_obs(), np.float32)
    np.testing.assert_allclose(load_networks(tmp_path).value(raw), v.squeeze(-1).numpy(), atol=1e-5)


def test_without_value_ignore_the_generator_keeps_the_full_width_critic():
    spec = load_spec(spec_file("tracelines"), TINY[:-1])
    model = build_model(spec, make_vec_env(spec, 2, 0))
    assert value_inputs(spec) is None and type(model.policy).__name__ == "LeanActorCriticPolicy"
