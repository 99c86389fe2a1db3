"""The discriminator's policy history: a uniform reservoir of raw transitions, fed back into each fit."""

import numpy as np
import pytest

import fastrl
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.data.replay import expert_trajectories
from fastrl.irl import AdversarialCallback, Discriminator, DiscriminatorFit, DiscriminatorForm, Transitions
from fastrl.irl.demonstrations import expert_transitions
from fastrl.irl.history import PolicyHistory
from fastrl.spec import load_spec

from ..conftest import spec_file

TINY = [
    "train.normalize.reward=false",
    "train.n_envs=2",
    "train.ppo.n_steps=64",
    "train.ppo.batch_size=64",
    "train.ppo.n_epochs=1",
    "episode.time_limit=2",
]


def rows(batch: int, n: int = 100) -> Transitions:
    """n transitions whose every entry is the batch number."""
    full = np.full((n, 3), batch, np.float32)
    return Transitions(full, full, np.zeros(n, np.float32), np.full((n, 1), batch, np.float32))


def test_reservoir_keeps_a_uniform_sample_of_everything_added():
    history = PolicyHistory(200, seed=0)
    with pytest.raises(ValueError, match="empty"):
        history.sample(1)
    for b in range(10):
        history.add(rows(b))
    assert len(history) == 200 and history.seen == 1000
    counts = np.bincount(history.data.obs[:, 0].astype(int), minlength=10)
    assert counts.sum() == 200 and counts.min() >= 8 and counts.max() <= 35  # 20 each expected, not the newest 200
    assert np.array_equal(history.data.obs[:, 0], history.data.actions[:, 0])  # rows stay whole
    drawn = history.sample(500)
    assert len(drawn) == 500 and set(np.unique(drawn.obs)) <= set(range(10))


def run_with_history(normalised: bool):
    """Two rollouts of a tiny AIRL run; its observation normalisation, if any, frozen at a mean of 3 and sd of 0.5."""
    spec = load_spec(spec_file("tracelines"), [*TINY, f"train.normalize.obs={str(normalised).lower()}"])
    expert = expert_transitions(fastrl.make(spec), expert_trajectories(fastrl.make(spec), range(2)))
    venv = make_vec_env(spec, 2, 0)
    if normalised:
        venv.obs_rms.mean[:], venv.obs_rms.var[:], venv.training = 3.0, 0.25, False
    model = build_model(spec, venv)
    cb = AdversarialCallback(
        DiscriminatorFit(
            Discriminator(venv.observation_space.shape[0], DiscriminatorForm(kind="airl", gamma=0.99)), batch_size=64
        ),
        expert,
        epochs=1,
        history=1000,
        scale_reward=True,
    )
    fitted = []
    fit_epochs = cb.fit.epochs
    cb.fit.epochs = lambda policy, expert, n: fitted.append(len(policy)) or fit_epochs(policy, expert, n)
    model.learn(256, callback=cb)
    return venv, model, cb, fitted


@pytest.fixture(scope="module")
def trained():
    """run_with_history with observation normalisation."""
    return run_with_history(True)


@pytest.mark.parametrize("normalised", [True, False])
def test_history_holds_the_rollouts_raw_transitions(trained, normalised):
    venv, model, cb, _ = trained if normalised else run_with_history(False)
    assert cb.history.seen == 256 and len(cb.history) == 256
    buf = model.rollout_buffer  # PPO's train() flattened it env-major
    n, e = 64, 2
    seen = buf.observations.reshape(e, n, -1).swapaxes(0, 1)
    norm = venv.normalize_obs if normalised else (lambda x: x)
    raw = np.stack(cb.raw_obs[:-1])
    assert not np.allclose(raw[1:], raw[:-1])  # the observations move
    np.testing.assert_allclose(norm(raw), seen, atol=1e-5)
    raw_next = np.stack(cb.raw_next)
    np.testing.assert_allclose(norm(raw_next), np.stack(cb.next_obs), atol=1e-5)


def test_terminal_observations_are_normalised_once(trained):
    _, _, cb, _ = trained
    nxt, raw = np.stack(cb.next_obs), np.stack(cb.raw_obs)
    done = np.any(raw[1:] != np.stack(cb.raw_next), axis=-1)  # rows where the env reset after the step
    assert done.any()
    # one control step moves a normalised observation little; normalising twice would move it by about 6
    step = np.abs(nxt[done] - (raw[:-1][done] - 3.0) / 0.5)
    assert np.median(step) < 1.0


def test_each_fit_adds_as_many_history_rows_as_the_rollout_has(trained):
    _, _, _, fitted = trained
    assert len(fitted) == 2
    assert fitted[1] >= 2 * 128 and fitted[0] < 2 * 128  # the first fit has no history yet
