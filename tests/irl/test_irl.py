"""Adversarial IRL: rewards are relabelled, AIRL's r_psi is separable, absorbing states, spectral norm, gradient
penalty, the ranking prior."""

from typing import get_args

import numpy as np
import pytest
import torch

import fastrl
from fastrl.agents.expert import ScriptedExpert
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.data.overlays import OVERLAYS
from fastrl.data.replay import expert_trajectories
from fastrl.irl import AdversarialCallback, Discriminator, DiscriminatorForm
from fastrl.irl.demonstrations import expert_transitions
from fastrl.irl.discriminator import absorbing_states, augment
from fastrl.irl.fitting import DiscriminatorFit, input_gradient_norm, make_batch
from fastrl.irl.ranking import RankedRollouts, noisy_expert_rollout, noisy_rollouts_batched, support_loss
from fastrl.runner.train.cloned import ClonedActor
from fastrl.spec import SpecError, load_spec
from fastrl.spec.columns import discriminator_inputs, reward_inputs
from fastrl.spec.irl import Degradation, DiscriminatorSettings

from ..conftest import spec_file

TINY = [
    "train.normalize.reward=false",
    "train.n_envs=2",
    "train.ppo.n_steps=64",
    "train.ppo.batch_size=64",
    "train.ppo.n_epochs=1",
    "episode.time_limit=8",
]


def ranking(noise: list[float], episodes: int, degraded: list[str] | bool = False) -> DiscriminatorSettings:
    """Ranking-prior settings: rates, rollouts per rate, and the overlays of the recordings' degraded copies."""
    return DiscriminatorSettings(ranking_noise=noise, ranking_episodes=episodes, ranking_degraded=degraded)


@pytest.fixture(scope="module")
def expert_data():
    """Expert transitions of two TraceLines demonstrations."""
    spec = load_spec(spec_file("tracelines"), TINY)
    return spec, expert_transitions(fastrl.make(spec), expert_trajectories(fastrl.make(spec), range(2)))


@pytest.mark.parametrize("kind", ["gail", "airl"])
def test_rollout_rewards_are_replaced_by_the_discriminator(expert_data, kind):
    spec, expert = expert_data
    assert expert.terminal[-1] == 1.0 and len(expert.obs) == len(expert.actions)
    venv = make_vec_env(spec, 2, 0)
    model = build_model(spec, venv)
    disc = Discriminator(venv.observation_space.shape[0], DiscriminatorForm(kind=kind, gamma=0.99))
    fit = DiscriminatorFit(disc, batch_size=64)
    cb = AdversarialCallback(fit, expert, epochs=1, scale_reward=False)  # scaling: test_irl_scaling
    before = [p.detach().clone() for p in disc.parameters()]
    model.learn(256, callback=cb)
    assert any(not torch.equal(a, b) for a, b in zip(before, disc.parameters()))
    assert {"irl/disc_loss", "irl/disc_accuracy", "irl/reward_policy", "irl/reward_expert"} <= set(cb.stats)
    buf = model.rollout_buffer
    env_rewards = np.stack(cb.env_rewards)
    assert not np.allclose(buf.rewards, env_rewards)
    # the relabelled rewards are the discriminator's, plus gamma V(absorbing) where an episode terminated
    n, e = buf.buffer_size, buf.n_envs
    terminal = np.stack(cb.terminal)

    def unswap(x):  # PPO's train() flattened the buffer env-major
        return x.reshape(e, n, -1).swapaxes(0, 1).reshape(n * e, -1)

    with torch.no_grad():
        s = augment(torch.as_tensor(unswap(buf.observations)))
        s2 = augment(torch.as_tensor(np.stack(cb.next_obs).reshape(n * e, -1)))
        t = torch.as_tensor(terminal.reshape(-1))
        lp = torch.as_tensor(unswap(buf.log_probs).reshape(-1))
        expected = disc.generator_reward(s, s2, t, lp).numpy().reshape(n, e)
    expected = expected + terminal * 0.99 * disc.absorbing_value()
    truncated = np.abs(buf.rewards - expected) > 1e-4  # truncations keep SB3's bootstrap on top
    assert truncated.mean() < 0.1
    np.testing.assert_allclose(buf.rewards[~truncated], expected[~truncated], rtol=1e-4, atol=1e-4)


def test_airl_reward_is_separable_from_the_shaping():
    disc = Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9, absorbing=False))
    s, s2 = augment(torch.randn(32, 6)), augment(torch.randn(32, 6))
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
        Discriminator(6, DiscriminatorForm(kind="gail", gamma=0.9)).reward(s)


def test_absorbing_states_keep_the_terminal_potential_and_value_the_end():
    disc = Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9, absorbing=True))
    s, s2 = augment(torch.randn(4, 6)), augment(torch.randn(4, 6))
    with torch.no_grad():
        kept = disc.reward(s) + 0.9 * disc.potential(s2) - disc.potential(s)
        assert torch.allclose(disc.f(s, s2, torch.ones(4)), kept)  # the episode goes on, absorbed
        a = absorbing_states(1, 6)
        r_abs = float(disc.f(a, a, torch.zeros(1))[0])
    assert disc.absorbing_value() == pytest.approx(r_abs / (1 - 0.9), rel=1e-5)
    assert torch.allclose(disc.terminal_bonus(torch.tensor([0.0, 1.0])), torch.tensor([0.0, 0.9 * r_abs / 0.1]))
    assert Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9, absorbing=False)).absorbing_value() == 0.0


def test_batches_get_one_absorbing_transition_per_terminated_episode():
    obs, nxt = np.random.randn(10, 6), np.random.randn(10, 6)
    term = np.zeros(10)
    term[[3, 9]] = 1
    batch = make_batch(obs, nxt, term, np.full(10, -1.0), absorbing=True)
    assert len(batch) == 12 and batch.s.shape == (12, 7)
    assert torch.equal(batch.s[10:, -1], torch.ones(2)) and torch.equal(batch.s[:10, -1], torch.zeros(10))
    assert torch.equal(batch.log_pi[10:], torch.zeros(2))
    assert len(make_batch(obs, nxt, term, np.zeros(10), absorbing=False)) == 10


def layer_norms_after_training(spectral: bool) -> list[float]:
    """Largest singular value of each linear layer after pushing the logits up for 50 steps."""
    torch.manual_seed(0)
    disc = Discriminator(8, DiscriminatorForm(kind="gail", gamma=0.99, hidden=(32, 32), spectral=spectral))
    optim = torch.optim.Adam(disc.parameters(), lr=1e-2)
    x = augment(torch.randn(256, 8) * 5)
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


def gradient_norm_after_fitting(kind: str, penalty: float) -> float:
    """Mean |grad_(s, s') logit| between policy and expert rows after 150 steps on two well-separated clouds."""
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    disc = Discriminator(6, DiscriminatorForm(kind=kind, gamma=0.99, hidden=(32, 32)))
    policy = make_batch(rng.normal(size=(128, 6)), rng.normal(size=(128, 6)), np.zeros(128), np.zeros(128), True)
    expert = make_batch(rng.normal(3, 1, (128, 6)), rng.normal(3, 1, (128, 6)), np.zeros(128), np.zeros(128), True)
    DiscriminatorFit(disc, lr=1e-2, batch_size=128, gradient_penalty=penalty).steps(policy, expert, 150)
    return float(input_gradient_norm(disc, policy, expert, torch.rand(128, 1)).mean().detach())


@pytest.mark.parametrize("kind", ["gail", "airl"])
def test_the_gradient_penalty_holds_the_logits_slope_near_one(kind):
    assert abs(gradient_norm_after_fitting(kind, 10.0) - 1.0) < 0.2
    assert gradient_norm_after_fitting(kind, 0.0) > 2.0  # without it the separable clouds steepen the logit


def test_standard_airl_is_one_network_on_transitions():
    disc = Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9, shaped=False))
    s, s2 = augment(torch.randn(8, 6)), augment(torch.randn(8, 6))
    with torch.no_grad():
        f = disc.net(torch.cat([s, s2], dim=-1)).squeeze(-1)
        assert torch.allclose(disc.f(s, s2, torch.zeros(8)), f)
        assert torch.allclose(disc.logits(s, s2, torch.zeros(8), torch.full((8,), -2.0)), f + 2.0)
    assert not hasattr(disc, "r_psi") and disc.config()["shaped"] is False
    with pytest.raises(ValueError, match="shaped"):
        disc.reward(s)


def test_airl_without_the_policy_term_ignores_log_pi():
    disc = Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9, policy_term=False))
    s, s2, term = augment(torch.randn(8, 6)), augment(torch.randn(8, 6)), torch.zeros(8)
    with torch.no_grad():
        assert torch.allclose(disc.logits(s, s2, term, torch.full((8,), 300.0)), disc.f(s, s2, term))
    assert (
        disc.config()["policy_term"] is False
        and Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9)).config()["policy_term"]
    )


@pytest.mark.parametrize("kind", ["gail", "airl"])
def test_a_discriminator_with_inputs_does_not_see_the_other_columns(kind):
    disc = Discriminator(6, DiscriminatorForm(kind=kind, gamma=0.9), inputs=[0, 1, 2, 4])
    first = next(m for m in disc.modules() if isinstance(m, torch.nn.Linear))
    assert first.in_features == (5 if kind == "airl" else 10)  # 4 columns and the absorbing flag (twice for GAIL)
    s, s2, term, lp = augment(torch.randn(8, 6)), augment(torch.randn(8, 6)), torch.zeros(8), torch.zeros(8)
    moved, moved2 = s.clone(), s2.clone()
    moved[:, [3, 5]] += 10.0
    moved2[:, [3, 5]] -= 10.0
    with torch.no_grad():
        assert torch.allclose(disc.logits(s, s2, term, lp), disc.logits(moved, moved2, term, lp))
        s[:, 4] += 10.0
        assert not torch.allclose(disc.logits(s, s2, term, lp), disc.logits(moved, moved2, term, lp))
    assert (
        disc.config()["inputs"] == [0, 1, 2, 4]
        and Discriminator(6, DiscriminatorForm(kind=kind, gamma=0.9)).config()["inputs"] is None
    )


def test_airl_reward_inputs_leave_columns_out_of_r_psi_but_not_of_h():
    disc = Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9), reward_inputs=[0, 1, 2, 3, 4])
    s = augment(torch.randn(8, 6))
    late = s.clone()
    late[:, 5] += 10.0  # the column r_psi does not see
    with torch.no_grad():
        assert torch.allclose(disc.reward(s), disc.reward(late))
        assert not torch.allclose(disc.potential(s), disc.potential(late))
        s[:, 4] += 10.0
        assert not torch.allclose(disc.reward(s), disc.reward(late))
    assert disc.config()["reward_inputs"] == [0, 1, 2, 3, 4] and disc.config()["inputs"] is None
    assert Discriminator(6, DiscriminatorForm(kind="airl", gamma=0.9), inputs=[0, 1]).config()["reward_inputs"] == [
        0,
        1,
    ]  # default: inputs


def test_reward_ignore_narrows_the_discriminator_inputs_for_r_psi():
    airl = load_spec(spec_file("tracelines"), ["irl.algorithm=airl", "irl.discriminator.reward_ignore=[elapsed]"])
    assert discriminator_inputs(airl) is None and reward_inputs(airl) == list(range(38))
    both = load_spec(
        spec_file("tracelines"),
        ["irl.algorithm=airl", "irl.discriminator.ignore=[contact]", "irl.discriminator.reward_ignore=[elapsed]"],
    )
    assert discriminator_inputs(both) == [*range(37), 38] and reward_inputs(both) == list(range(37))
    plain = load_spec(spec_file("tracelines"), ["irl.algorithm=airl", "irl.discriminator.reward_ignore=[]"])
    assert reward_inputs(plain) is None


def test_gail_ignores_the_clock_by_default_and_airl_sees_it():
    gail = load_spec(spec_file("imagecentring"), ["irl.algorithm=gail"])
    terms = gail.observation.terms()
    assert terms[-1] == "elapsed" and discriminator_inputs(gail) == list(range(38))  # 39 columns, the last one
    assert discriminator_inputs(load_spec(spec_file("imagecentring"), ["irl.algorithm=airl"])) is None
    assert (
        discriminator_inputs(
            load_spec(spec_file("imagecentring"), ["irl.algorithm=gail", "irl.discriminator.ignore=[]"])
        )
        is None
    )
    stacked = load_spec(
        spec_file("imagecentring"),
        ["irl.algorithm=airl", "observation.stack=2", "irl.discriminator.ignore=[contact, elapsed]"],
    )
    assert discriminator_inputs(stacked) == [*range(37), *range(39, 76)]


@pytest.mark.parametrize("kind", ["gail", "airl"])
def test_absorbing_rows_train_only_the_absorbing_constants(kind):
    torch.manual_seed(0)
    disc = Discriminator(6, DiscriminatorForm(kind=kind, gamma=0.99, hidden=(16, 16), spectral=True))
    ends = make_batch(np.random.randn(4, 6), np.random.randn(4, 6), np.ones(4), np.zeros(4), absorbing=True)
    absorbed = ends.take(slice(4, 8))  # the four absorbing rows appended for four terminated episodes
    assert torch.equal(absorbed.s[:, -1], torch.ones(4)) and torch.equal(absorbed.s[:, :-1], torch.zeros(4, 6))
    z = disc.logits(absorbed.s, absorbed.s2, absorbed.terminal, absorbed.log_pi)
    torch.nn.functional.binary_cross_entropy_with_logits(z, torch.ones(4)).backward()
    for name, p in disc.named_parameters():
        moved = p.grad is not None and bool(p.grad.abs().sum() > 0)
        assert moved == ("r_absorbing" in name or (kind == "airl" and "h_absorbing" in name and disc.gamma != 1)), name
    fit = DiscriminatorFit(disc, lr=1e-2, batch_size=4)
    policy = make_batch(np.random.randn(4, 6), np.random.randn(4, 6), np.zeros(4), np.zeros(4), absorbing=True)
    for _ in range(50):  # the expert always ends, the policy never: ending becomes worth more
        fit._fit(policy, absorbed, [np.arange(4)])
    assert disc.absorbing_value() > 5.0  # a free constant, whatever the spectral norm does to the networks


def test_noiseless_ranking_rollouts_are_the_experts_and_end_in_the_absorbing_state():
    spec = load_spec(spec_file("tracelines"))
    env = fastrl.make(spec)
    expert_obs = expert_transitions(env, expert_trajectories(env, [7])).obs
    obs, ended = noisy_expert_rollout(env, ScriptedExpert(env), 0.0, 7)
    assert ended and np.allclose(obs[:-1], expert_obs, atol=1e-5)
    ranked = RankedRollouts(env, ranking([0.0, 1.0], 1), seed=7)
    s = ranked.states(lambda o: o)
    assert torch.equal(s[0, len(obs) :, -1], torch.ones(s.shape[1] - len(obs)))  # absorbed after the task is done
    assert torch.equal(s[0, len(obs) :, :-1], torch.zeros(s.shape[1] - len(obs), s.shape[2] - 1))
    assert not ranked.absorbed[1].any()  # random actions do not finish TraceLines


def test_the_ranking_loss_teaches_r_psi_that_less_noise_is_better():
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=8"])
    ranked = RankedRollouts(fastrl.make(spec), ranking([0.0, 0.5, 1.0], 2), snippet=20)
    torch.manual_seed(0)
    disc = Discriminator(ranked.raw.shape[2], DiscriminatorForm(kind="airl", gamma=0.99, hidden=(32, 32)))
    states, rng = ranked.states(lambda o: o), np.random.default_rng(0)
    optim = torch.optim.Adam(disc.parameters(), lr=1e-3)
    with torch.no_grad():
        first = float(ranked.loss(disc, states, rng))
    for _ in range(200):
        loss = ranked.loss(disc, states, rng)
        optim.zero_grad()
        loss.backward()
        optim.step()
    with torch.no_grad():
        totals = disc.reward(states).sum(-1).numpy()
        assert float(ranked.loss(disc, states, rng)) < first
    means = [totals[ranked.noise == eps].mean() for eps in (0.0, 0.5, 1.0)]
    assert means[0] > means[1] > means[2], means


def test_the_support_loss_teaches_r_psi_that_demonstrated_states_beat_their_noisy_copies(expert_data):
    obs = expert_data[1].obs
    shown = augment(torch.as_tensor((obs - obs.mean(0)) / (obs.std(0) + 1e-6), dtype=torch.float32))
    torch.manual_seed(0)
    disc = Discriminator(obs.shape[1], DiscriminatorForm(kind="airl", gamma=0.99, hidden=(32, 32)))
    rng = np.random.default_rng(0)
    assert float(support_loss(disc, shown, rng, 0.0)) == 0.0
    assert rng.bit_generator.state == np.random.default_rng(0).bit_generator.state  # off: draws nothing
    optim = torch.optim.Adam(disc.parameters(), lr=1e-3)
    with torch.no_grad():
        first = float(support_loss(disc, shown, np.random.default_rng(1), 1.0))
    for _ in range(200):
        loss = support_loss(disc, shown, rng, 1.0)
        optim.zero_grad()
        loss.backward()
        optim.step()
    with torch.no_grad():
        assert float(support_loss(disc, shown, np.random.default_rng(1), 1.0)) < 0.5 * first
        noisy = shown + torch.as_tensor(np.random.default_rng(2).standard_normal(shown.shape), dtype=torch.float32)
        noisy[:, -1] = 0.0
        above = (disc.reward(shown) > disc.reward(noisy)).float().mean()
    assert float(above) > 0.8  # fresh noisy copies: the demonstrated state is rated higher


def test_a_held_random_action_is_repeated_for_its_steps():
    env = fastrl.make(load_spec(spec_file("tracelines"), ["episode.time_limit=4"]))
    obs, _ = noisy_expert_rollout(env, ScriptedExpert(env), 1.0, 3, repeat=1000)  # one random action, held
    env.action_space.seed(3)
    action = env.action_space.sample()
    held = [env.reset(seed=3)[0]] + [env.step(action)[0] for _ in range(len(obs) - 1)]
    assert np.allclose(obs, np.array(held), atol=1e-6)
    varied, _ = noisy_expert_rollout(env, ScriptedExpert(env), 1.0, 3, repeat=1)
    assert not np.allclose(varied, obs)


def test_a_batch_actor_rolls_out_in_lockstep_exactly_as_one_at_a_time():
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=4"])
    env = fastrl.make(spec)
    w = np.random.default_rng(0).normal(size=(env.action_space.n, env.observation_space.shape[0]))
    batch = lambda obs: np.argmax(obs @ w.T, axis=1)  # noqa: E731  a stateless deterministic policy
    actor = ClonedActor(lambda obs: int(batch(obs[None])[0]), batch)
    noise, seeds = [0.0, 0.5, 1.0], [11, 12, 13]
    one = [noisy_expert_rollout(env, actor, eps, seed, repeat=3) for eps, seed in zip(noise, seeds)]
    both = noisy_rollouts_batched([fastrl.make(spec) for _ in seeds], batch, noise, seeds, repeat=3)
    for (a, end_a), (b, end_b) in zip(one, both):
        assert a.shape == b.shape and np.array_equal(a, b) and end_a == end_b
    assert not np.array_equal(one[0][0], one[2][0])  # the noise changed the rollout
    ranked = RankedRollouts(env, ranking(noise, 1), seed=11, actor=actor, envs=[fastrl.make(spec) for _ in noise])
    slow = RankedRollouts(env, ranking(noise, 1), seed=11, actor=actor)
    assert np.array_equal(ranked.raw, slow.raw) and np.array_equal(ranked.absorbed, slow.absorbed)


def test_degraded_copies_of_recordings_are_ranked_against_each_other_only():
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=8"])
    env = fastrl.make(spec)
    recordings = expert_trajectories(env, [1, 2])
    ranked = RankedRollouts(env, ranking([0.0, 0.5, 1.0], 1, ["drift", "paused"]), snippet=20, recordings=recordings)
    copies = ranked.source == 1
    assert copies.sum() == 6 and sorted(ranked.noise[copies]) == [0.0, 0.0, 0.5, 0.5, 1.0, 1.0]
    clean = np.flatnonzero(copies & (ranked.noise == 0.0))[0]
    expected = expert_transitions(env, recordings[:1]).obs
    assert np.allclose(ranked.raw[clean, : len(expected)], expected, atol=1e-5)  # eps 0: the recording as it was
    worst = np.flatnonzero(copies & (ranked.noise == 1.0))[0]
    assert not np.allclose(ranked.raw[worst, : len(expected)], expected, atol=1e-3)  # drifted and paused
    better, worse = ranked.pairs(np.random.default_rng(0), 400)
    assert len(better) > 50 and (ranked.source[better] == ranked.source[worse]).all()  # never across sources
    assert (ranked.noise[better] < ranked.noise[worse]).all()
    assert (ranked.source[better] == 1).any() and (ranked.source[better] == 0).any()


def test_degraded_copies_name_overlays_that_exist_and_true_keeps_drift_jitter_slowed():
    assert set(get_args(Degradation)) == set(OVERLAYS)
    assert ranking([0.0, 1.0], 1, True).degraded_overlays == ("drift", "jitter", "slowed")
    assert ranking([0.0, 1.0], 1, False).degraded_overlays == ()
    assert ranking([0.0, 1.0], 1, ["paused"]).degraded_overlays == ("paused",)
    with pytest.raises(SpecError) as e:
        load_spec(spec_file("tracelines"), ["irl.discriminator.ranking_degraded=[wobble]"])
    assert "ranking_degraded" in str(e.value)
