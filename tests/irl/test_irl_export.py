"""Pickle-free export of IRL networks: the loaded policy, value and reward (evaluated with numpy) reproduce SB3 and
the discriminator (torch) to float32 tolerance; safetensors files load without fastrl."""

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch
from safetensors import safe_open
from safetensors.torch import load_file, save_file

from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.assess.scoring import learned_scores
from fastrl.env import FastEnv
from fastrl.irl import Discriminator, DiscriminatorForm
from fastrl.irl.discriminator import absorbing_states, augment
from fastrl.irl.export import load_networks, reward_snapshot, save_networks
from fastrl.irl.fitting import Transitions
from fastrl.spec import load_spec

from ..conftest import spec_file

PPO_TINY = ["train.n_envs=2", "train.ppo.n_steps=16", "train.ppo.batch_size=32"]
SAC_TINY = [
    "actions.mode=continuous",
    "train.algo=SAC",
    "train.n_envs=2",
    "train.sac.learning_starts=50",
    "train.sac.batch_size=32",
]
GAMMA = 0.9
FILES = {"policy.safetensors", "value.safetensors", "reward.safetensors"}


def read_header(path) -> dict:
    """The JSON description in a safetensors file's header."""
    with safe_open(str(path), "pt") as f:
        return json.loads(f.metadata()["fastrl"])


def edit_header(d, name, edit) -> None:
    """Rewrite NAME.safetensors with its header description changed by edit(meta)."""
    path = d / f"{name}.safetensors"
    meta, tensors = read_header(path), load_file(str(path))
    edit(meta)
    save_file(tensors, str(path), metadata={"fastrl": json.dumps(meta)})


def raw_observations(spec, n: int, seed: int = 0) -> np.ndarray:
    """n + 1 consecutive raw observations of one random-action episode (restarted if it ends)."""
    env = FastEnv(spec)
    env.action_space.seed(seed)
    obs, _ = env.reset(seed=seed)
    out = [obs]
    while len(out) <= n:
        obs, _, terminated, truncated, _ = env.step(env.action_space.sample())
        out.append(obs)
        if terminated or truncated:
            obs, _ = env.reset()
    return np.asarray(out, dtype=np.float32)


def trained(spec_overrides):
    """A tiny model trained for 200 steps (so VecNormalize's statistics moved) and 51 raw observations."""
    spec = load_spec(spec_file("tracelines"), spec_overrides)
    venv = make_vec_env(spec, 2, 0)
    model = build_model(spec, venv)
    model.learn(200)
    obs = raw_observations(spec, 50)
    assert not np.allclose(venv.normalize_obs(obs), obs, atol=1e-3)  # the normalisation is really exercised
    return model, venv, obs


@pytest.fixture(scope="module")
def ppo_run():
    return trained(PPO_TINY)


@pytest.fixture(scope="module")
def sac_run():
    return trained(SAC_TINY)


def spectral_disc(
    obs_dim: int, kind: str, absorbing: bool = True, shaped: bool = True, inputs=None, reward_inputs=None, seed: int = 1
) -> Discriminator:
    """A spectrally normalised discriminator after a few training steps (weights and power iterates moved)."""
    torch.manual_seed(seed)
    disc = Discriminator(
        obs_dim,
        DiscriminatorForm(kind=kind, gamma=GAMMA, hidden=(16, 16), spectral=True, absorbing=absorbing, shaped=shaped),
        inputs=inputs,
        reward_inputs=reward_inputs,
    )
    opt = torch.optim.Adam(disc.parameters(), lr=1e-2)
    for _ in range(5):
        a = absorbing_states(4, obs_dim)  # absorbing rows train the absorbing constants away from 0
        s, s2 = torch.cat([augment(torch.randn(32, obs_dim)), a]), torch.cat([augment(torch.randn(32, obs_dim)), a])
        loss = (disc.logits(s, s2, torch.zeros(36), torch.zeros(36)) - 1.0).square().mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    return disc


def normalized_states(venv, obs) -> torch.Tensor:
    """Discriminator inputs as the IRL loops build them: normalised observations with the absorbing flag."""
    return augment(torch.as_tensor(venv.normalize_obs(obs)))


def test_ppo_policy_and_value_match_sb3(ppo_run, tmp_path):
    model, venv, obs = ppo_run
    save_networks(tmp_path, model, venv, spectral_disc(obs.shape[1], "airl"), GAMMA)
    paths = save_networks(tmp_path, model, venv, None, GAMMA)  # no discriminator: a stale reward is removed
    assert {p.name for p in paths} == FILES - {"reward.safetensors"}
    assert {p.name for p in tmp_path.iterdir()} == {p.name for p in paths}
    nets = load_networks(tmp_path)
    x = venv.normalize_obs(obs)
    expected, _ = model.predict(x, deterministic=True)
    actions = nets.policy(obs)
    assert len(np.unique(expected)) > 1 and actions.shape == expected.shape
    np.testing.assert_array_equal(actions, expected)
    with torch.no_grad():
        values = model.policy.predict_values(torch.as_tensor(x)).squeeze(-1).numpy()
    np.testing.assert_allclose(nets.value(obs), values, atol=1e-5)
    with pytest.raises(ValueError, match="no reward network"):
        nets.reward(obs)


def test_sac_policy_and_value_match_sb3(sac_run, tmp_path):
    model, venv, obs = sac_run
    save_networks(tmp_path, model, venv, None, GAMMA)
    nets = load_networks(tmp_path)
    x = venv.normalize_obs(obs)
    expected, _ = model.predict(x, deterministic=True)
    actions = nets.policy(obs)
    assert actions.shape == expected.shape and np.ptp(expected, axis=0).min() > 1e-3
    np.testing.assert_allclose(actions, expected, atol=1e-5)
    with torch.no_grad():
        xt = torch.as_tensor(x)
        q1 = model.critic(xt, model.actor(xt, deterministic=True))[0].squeeze(-1).numpy()
    np.testing.assert_allclose(nets.value(obs), q1, atol=1e-5)


def test_airl_reward_and_potential_match_the_spectral_discriminator(ppo_run, tmp_path):
    model, venv, obs = ppo_run
    disc = spectral_disc(obs.shape[1], "airl")
    before = {k: v.clone() for k, v in disc.state_dict().items()}
    save_networks(tmp_path, model, venv, disc, GAMMA)
    assert all(torch.equal(before[k], v) for k, v in disc.state_dict().items())  # no power-iteration step
    assert disc.training
    weights = load_file(str(tmp_path / "reward.safetensors"))
    raw = disc.r_psi[0].parametrizations.weight.original
    assert not torch.allclose(weights["r_psi.0.weight"], raw, atol=1e-3)  # the effective weight W / sigma
    disc.eval()
    s = normalized_states(venv, obs)
    nets = load_networks(tmp_path)
    with torch.no_grad():
        np.testing.assert_allclose(nets.reward(obs), disc.reward(s[:-1]).numpy(), atol=1e-5)
        np.testing.assert_allclose(nets.potential(obs), disc.potential(s).numpy(), atol=1e-5)
    assert nets.reward(obs).shape == (len(obs) - 1,)
    assert nets.kind == "airl" and nets.gamma == GAMMA


def test_a_saved_reward_keeps_the_columns_r_psi_and_h_saw(ppo_run, tmp_path):
    model, venv, obs = ppo_run
    d = obs.shape[1]
    disc = spectral_disc(d, "airl", inputs=list(range(1, d)), reward_inputs=list(range(1, d - 1)))
    save_networks(tmp_path, model, venv, disc, GAMMA)
    disc.eval()
    nets = load_networks(tmp_path)
    s = normalized_states(venv, obs)
    with torch.no_grad():
        np.testing.assert_allclose(nets.reward(obs), disc.reward(s[:-1]).numpy(), atol=1e-5)
        np.testing.assert_allclose(nets.potential(obs), disc.potential(s).numpy(), atol=1e-5)
    moved = obs.copy()
    moved[:, -1] += 1.0  # seen by h only
    assert np.allclose(nets.reward(moved), nets.reward(obs)) and not np.allclose(
        nets.potential(moved), nets.potential(obs)
    )


@pytest.mark.parametrize("kind", ["gail", "airl"])
def test_transition_rewards_are_the_logit_of_consecutive_states(ppo_run, tmp_path, kind):
    model, venv, obs = ppo_run
    disc = spectral_disc(obs.shape[1], kind, shaped=False)  # GAIL, and AIRL's standard (unshaped) form
    save_networks(tmp_path, model, venv, disc, GAMMA)
    disc.eval()
    s = normalized_states(venv, obs)
    zeros = torch.zeros(len(s) - 1)
    nets = load_networks(tmp_path)
    with torch.no_grad():
        np.testing.assert_allclose(nets.reward(obs), disc.logits(s[:-1], s[1:], zeros, zeros).numpy(), atol=1e-5)
    with pytest.raises(ValueError, match="shaping potential"):
        nets.potential(obs)


@pytest.mark.parametrize("kind", ["airl", "gail"])
def test_learned_return_adds_the_absorbing_value_only_when_terminated(ppo_run, tmp_path, kind):
    model, venv, obs = ppo_run
    disc = spectral_disc(obs.shape[1], kind)
    save_networks(tmp_path, model, venv, disc, GAMMA)
    disc.eval()
    a = absorbing_states(1, obs.shape[1])
    with torch.no_grad():  # the unshaped learned reward of the absorbing state, as reward() gives it
        r_abs = float(disc.reward(a)[0] if kind == "airl" else disc.logits(a, a, torch.zeros(1), torch.zeros(1))[0])
    assert abs(r_abs) > 1e-4
    nets = load_networks(tmp_path)
    assert nets.absorbing_reward() == pytest.approx(r_abs, rel=1e-5, abs=1e-6)
    r, big_t = nets.reward(obs).astype(np.float64), len(obs) - 1
    truncated = nets.learned_return(obs, terminated=False)
    assert truncated == pytest.approx(float(np.sum(GAMMA ** np.arange(big_t) * r)), rel=1e-9, abs=1e-9)
    terminated = nets.learned_return(obs, terminated=True)
    assert terminated - truncated == pytest.approx(GAMMA**big_t * r_abs / (1 - GAMMA), rel=1e-5, abs=1e-6)
    short = obs[:4]  # a short episode: the absorbing value weighs more
    diff = nets.learned_return(short, True, gamma=0.5) - nets.learned_return(short, False, gamma=0.5)
    assert diff == pytest.approx(0.5**3 * r_abs / 0.5, rel=1e-5)


@pytest.mark.parametrize("kind", ["airl", "gail"])
def test_reward_and_value_count_from_the_best_demonstrated_step(ppo_run, tmp_path, kind):
    model, venv, obs = ppo_run
    disc = spectral_disc(obs.shape[1], kind)
    save_networks(tmp_path, model, venv, disc, GAMMA)
    old = load_networks(tmp_path)  # saved without demonstrations: the raw sum and the mean value
    assert (old.reward_ceiling, old.value_ceiling) == (0.0, None)
    assert learned_scores(old, obs)["value"] == pytest.approx(float(old.value(obs).mean()), rel=1e-6)
    shown = Transitions(obs[:-1], obs[1:], np.zeros(len(obs) - 1, np.float32), np.zeros((len(obs) - 1, 1)))
    save_networks(tmp_path, model, venv, disc, GAMMA, demonstrations=shown.take(slice(0, 12)))
    nets = load_networks(tmp_path)
    r, v = nets.reward(obs), nets.value(obs)
    assert nets.reward_ceiling == pytest.approx(float(r[:12].max()), abs=1e-6)
    assert nets.value_ceiling == pytest.approx(float(v[:12].max()), abs=1e-6)
    assert nets.reward_ceiling != pytest.approx(float(r.max()), abs=1e-6)  # only the demonstrated steps count
    assert nets.value_ceiling != pytest.approx(float(v.max()), abs=1e-6)
    scores = learned_scores(nets, obs)
    assert scores["reward"] == pytest.approx(float((r - nets.reward_ceiling).sum()), rel=1e-6)
    assert scores["value"] == pytest.approx(float((v - nets.value_ceiling).sum()), rel=1e-6)
    assert scores["rewards"][:12].max() == pytest.approx(0.0, abs=1e-6)
    assert scores["values"][:12].max() == pytest.approx(0.0, abs=1e-6)
    longer = np.concatenate([obs, obs[-1:].repeat(20, 0)])  # the last state held: the same states, more steps
    held = learned_scores(nets, longer)["value"]
    assert held == pytest.approx(scores["value"] + 20 * (v[-1] - nets.value_ceiling), rel=1e-5)
    assert held < scores["value"]  # the held state is below the ceiling: more steps of it cost more
    per = learned_scores(nets, obs, reached=3)  # one who stopped on the third subtask: the cost of each
    assert (per["reward"], per["value"]) == pytest.approx((scores["reward"] / 3, scores["value"] / 3), rel=1e-12)
    assert learned_scores(old, obs, reached=3)["value"] == pytest.approx(float(old.value(obs).mean()), rel=1e-6)
    for name in ("reward", "value"):
        for bad in ("high", float("nan")):
            edit_header(tmp_path, name, lambda m, bad=bad: m.update(ceiling=bad))
            with pytest.raises(ValueError, match=f"{name}.safetensors: ceiling must be a finite number"):
                load_networks(tmp_path)
        save_networks(tmp_path, model, venv, disc, GAMMA, demonstrations=shown)


def test_an_averaged_reward_is_the_mean_of_its_members_each_under_its_own_normalisation(ppo_run, tmp_path):
    model, venv, obs = ppo_run
    d = obs.shape[1]
    early, final = spectral_disc(d, "airl", seed=2), spectral_disc(d, "airl", seed=3)
    snapshots = [reward_snapshot(early, venv)]
    saved_mean = venv.obs_rms.mean.copy()
    try:
        venv.obs_rms.mean = saved_mean + 0.5  # the statistics move on after the snapshot
        save_networks(tmp_path, model, venv, final, GAMMA, [*snapshots, reward_snapshot(final, venv)])
        s_final = normalized_states(venv, obs)
    finally:
        venv.obs_rms.mean = saved_mean
    s_early = normalized_states(venv, obs)
    early.eval()
    final.eval()
    nets, last = load_networks(tmp_path), load_networks(tmp_path, averaged=False)
    assert (nets.reward_members, last.reward_members) == (2, 1)  # the snapshot equal to the final one is dropped
    with torch.no_grad():
        r_early, r_final = early.reward(s_early[:-1]).numpy(), final.reward(s_final[:-1]).numpy()
        h_early, h_final = early.potential(s_early).numpy(), final.potential(s_final).numpy()
        r_abs = [float(early.r_absorbing), float(final.r_absorbing)]
    assert not np.allclose(r_early, r_final, atol=1e-2)
    np.testing.assert_allclose(nets.reward(obs), (r_early + r_final) / 2, atol=1e-5)
    np.testing.assert_allclose(nets.potential(obs), (h_early + h_final) / 2, atol=1e-5)
    np.testing.assert_allclose(last.reward(obs), r_final, atol=1e-5)
    assert nets.absorbing_reward() == pytest.approx(np.mean(r_abs), rel=1e-5)
    edit_header(tmp_path, "reward", lambda m: m["average"].update(members=3))  # a member whose tensors are missing
    with pytest.raises(ValueError, match="reward.safetensors.*average.2"):
        load_networks(tmp_path)
    edit_header(tmp_path, "reward", lambda m: m.update(average=[2]))  # malformed: named, not a crash
    with pytest.raises(ValueError, match="reward.safetensors.*average.members"):
        load_networks(tmp_path)


def test_without_absorbing_states_termination_adds_nothing(ppo_run, tmp_path):
    model, venv, obs = ppo_run
    save_networks(tmp_path, model, venv, spectral_disc(obs.shape[1], "airl", absorbing=False), GAMMA)
    nets = load_networks(tmp_path)
    assert nets.learned_return(obs, True) == nets.learned_return(obs, False)


@pytest.fixture(scope="module")
def exported(ppo_run, tmp_path_factory):
    """A PPO + AIRL export to copy and corrupt."""
    model, venv, obs = ppo_run
    out = tmp_path_factory.mktemp("exported")
    save_networks(out, model, venv, spectral_disc(obs.shape[1], "airl"), GAMMA)
    return out


def _truncate_safetensors(d):
    data = (d / "policy.safetensors").read_bytes()
    (d / "policy.safetensors").write_bytes(data[: len(data) // 2])


def _no_description(d):
    path = d / "value.safetensors"
    save_file(load_file(str(path)), str(path))


SAFETENSORS_CORRUPTIONS = {
    "truncated": (_truncate_safetensors, ValueError, "policy.safetensors.*not a readable"),
    "no description": (_no_description, ValueError, "value.safetensors.*'fastrl'"),
    "missing layer width": (
        lambda d: edit_header(d, "policy", lambda m: m["parts"]["pi"][0].pop("in")),
        ValueError,
        "policy.safetensors",
    ),
    "wrong layer width": (
        lambda d: edit_header(d, "value", lambda m: m["parts"]["v"][0].update({"in": 3})),
        ValueError,
        "value.safetensors",
    ),
    "missing absorbing value": (
        lambda d: edit_header(d, "reward", lambda m: m.pop("absorbing_value")),
        ValueError,
        "reward.safetensors.*absorbing_value",
    ),
    "missing file": (lambda d: (d / "value.safetensors").unlink(), FileNotFoundError, "value.safetensors"),
    "missing obs_norm": (
        lambda d: edit_header(d, "reward", lambda m: m.pop("obs_norm")),
        ValueError,
        "reward.safetens",
    ),
    "unknown output": (
        lambda d: edit_header(d, "policy", lambda m: m.update({"output": "sample"})),
        ValueError,
        "policy.safetensors",
    ),
    "bad reward columns": (
        lambda d: edit_header(d, "reward", lambda m: m.update({"reward_inputs": [0, -1]})),
        ValueError,
        "reward.safetensors.*reward_inputs",
    ),
}


@pytest.mark.parametrize("name", list(SAFETENSORS_CORRUPTIONS))
def test_corrupted_safetensors_raise_errors_naming_the_file(exported, tmp_path, name):
    corrupt, error, match = SAFETENSORS_CORRUPTIONS[name]
    d = tmp_path / "nets"
    shutil.copytree(exported, d)
    corrupt(d)
    with pytest.raises(error, match=match):
        load_networks(d)


def test_every_file_is_safetensors_with_its_description_in_the_header(exported):
    assert {p.name for p in exported.iterdir()} == FILES  # no temporary files left behind
    for name in ("policy", "value", "reward"):
        tensors = load_file(str(exported / f"{name}.safetensors"))
        assert tensors and all(isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in tensors.items())
        meta = read_header(exported / f"{name}.safetensors")
        assert meta["format"] == "fastrl.networks/1" and meta["network"] == name
        assert meta["obs_norm"] is not None and {"obs_norm.mean", "obs_norm.var"} <= set(tensors)
        linear = [(i, layer) for i, layer in enumerate(next(iter(meta["parts"].values()))) if layer["type"] == "linear"]
        assert linear and all(f"{next(iter(meta['parts']))}.{i}.weight" in tensors for i, _ in linear)
    reward = read_header(exported / "reward.safetensors")
    assert {"kind", "gamma", "absorbing", "absorbing_value"} <= set(reward) and reward["kind"] == "airl"


# The documented lines: a value network evaluated with safetensors and torch alone (no fastrl), read from
# docs/networks.md (which the README links).
NETWORKS_DOC = Path(__file__).resolve().parents[2] / "docs" / "networks.md"


def readme_snippet() -> str:
    """The documented python block that loads a network with safetensors."""
    blocks = re.findall(r"```python\n(.*?)```", NETWORKS_DOC.read_text(), flags=re.S)
    return next(b for b in blocks if "safetensors" in b)


def test_the_readme_lines_evaluate_a_value_network_without_fastrl(exported, ppo_run, tmp_path):
    _, _, obs = ppo_run
    shutil.copytree(exported, tmp_path / "networks")
    np.save(tmp_path / "obs.npy", obs.astype(np.float64))
    script = "import numpy, torch\nobs = torch.as_tensor(numpy.load('obs.npy'))\n" + readme_snippet()
    script += "\nimport sys\nassert not any(m.startswith('fastrl') for m in sys.modules)\n"
    script += "numpy.save('value.npy', value.numpy())\n"
    res = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    np.testing.assert_allclose(np.load(tmp_path / "value.npy"), load_networks(exported).value(obs), atol=1e-5)
