"""Pixel policies end to end on tiny budgets: the encoder, `fastrl run` from images, its recording and checkpoint."""

import json

import numpy as np
import pytest
import torch
from gymnasium import spaces
from typer.testing import CliRunner

from fastrl.agents.encoder import PixelEncoder, random_shift
from fastrl.cli import app
from fastrl.env.fast_env import FastEnv
from fastrl.runner.runs.saved import load_policy
from fastrl.spec import load_spec

from ..conftest import spec_file
from .test_runner import only_run, recorded, rrd_verify

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

PIXELS = spec_file("tracelines_pixels")
TINY = [
    "train.n_envs=4",
    "train.workers=2",
    "train.ppo.n_steps=32",
    "train.ppo.batch_size=64",
    "train.ppo.n_epochs=1",
    "train.log_every=128",
    "train.checkpoint_every=128",
    "evaluate.episodes=2",
    "evaluate.record_episodes=2",
    "evaluate.image_every=10",
    "evaluate.periodic_every=0",
    "evaluate.expert=false",
    "episode.time_limit=3",
    "observation.image.size=32",
]


def test_random_shift_moves_whole_images_by_at_most_pad():
    torch.manual_seed(0)
    x = torch.arange(2 * 3 * 8 * 8, dtype=torch.float32).view(2, 3, 8, 8)
    y = random_shift(x, 2)
    assert y.shape == x.shape
    for n in range(2):  # every output is a window of the edge-padded input
        padded = torch.nn.functional.pad(x[n : n + 1], (2, 2, 2, 2), mode="replicate")[0]
        windows = [padded[:, i : i + 8, j : j + 8] for i in range(5) for j in range(5)]
        assert any(torch.equal(y[n], w) for w in windows)
    assert not all(torch.equal(random_shift(x, 2), x) for _ in range(5))


def test_encoder_shifts_only_in_training_and_keeps_the_state():
    image = spaces.Box(0, 255, (6, 32, 32), np.uint8)
    both = spaces.Dict({"image": image, "state": spaces.Box(-1, 1, (5,), np.float32)})
    enc = PixelEncoder(both, features=16, shift=4)
    obs = {"image": torch.rand(3, 6, 32, 32), "state": torch.rand(3, 5)}
    enc.eval()
    a, b = enc(obs), enc(obs)
    assert a.shape == (3, 21) and torch.equal(a, b) and torch.equal(a[:, 16:], obs["state"])
    enc.train()
    assert not torch.equal(enc(obs)[:, :16], a[:, :16])


def test_pixel_ppo_run_end_to_end_with_the_policys_frames_recorded(tmp_path):
    args = ["run", str(PIXELS), "--timesteps", "256", *[a for kv in TINY for a in ("--set", kv)]]
    args += ["--set", "train.warm_start=null"]  # the shipped warm start takes minutes; it has its own test below
    res = CliRunner().invoke(app, [*args, "--runs", str(tmp_path), "--no-progress"])
    assert res.exit_code == 0, res.output
    run = only_run(tmp_path)
    meta = json.loads((run / "meta.json").read_text())
    assert meta["status"] == "done" and meta["trained_timesteps"] >= 256
    ev = json.loads((run / "eval.json").read_text())
    assert ev["agent"]["episodes"] == 2
    assert "1 file verified" in rrd_verify(run / "recording.rrd")
    entities, _ = recorded(run / "recording.rrd")
    assert {"/world/eval/ep_00/policy", "/world/eval/ep_00/camera/image", "/world/eval/ep_01/policy"} <= entities
    spec, policy = load_policy(run)  # the saved CNN policy acts on frames as the trained one did
    assert spec.observation.image.size == 32
    env = FastEnv(spec)
    obs, _ = env.reset(seed=3)
    assert obs.shape == (32, 32, 6) and obs.dtype == np.uint8
    actions = [policy(env.step(policy(obs))[0]) for _ in range(3)]
    assert all(0 <= int(a) < 11 for a in actions)


def test_pixel_spec_sees_no_kinematic_state():
    spec = load_spec(PIXELS)
    env = FastEnv(spec)
    assert isinstance(env.observation_space, spaces.Box) and env.observation_space.dtype == np.uint8
    assert env.observation_space.shape == (48, 48, 6)


def test_pixel_sac_learns_a_few_steps_and_its_buffer_is_bounded():
    from fastrl.agents.sb3 import build_model, make_vec_env
    from fastrl.spec import SpecError

    base = ["train.algo=SAC", "actions.mode=rates", "observation.image.size=32", "train.warm_start=null"]
    try:
        load_spec(PIXELS, base)  # 300k frames of 32 x 32 x 6, twice: 3.7 GB, under the limit
        load_spec(PIXELS, [*base, "observation.image.size=48"])
    except SpecError as e:
        assert "GB of memory" in str(e)
    else:
        raise AssertionError("an 8 GB replay buffer of frames was accepted")
    small = [*base, "train.sac.buffer_size=1000", "train.sac.learning_starts=32", "train.sac.batch_size=16"]
    spec = load_spec(PIXELS, [*small, "train.n_envs=2"])
    venv = make_vec_env(spec, 2, 0, workers=1)
    model = build_model(spec, venv)
    assert isinstance(model.policy.actor.features_extractor, PixelEncoder)
    model.learn(64)
    assert model.num_timesteps == 64 and model.replay_buffer.observations.dtype == np.uint8
    venv.close()


def test_behaviour_cloning_fits_a_pixel_policy_to_expert_frames(tmp_path):
    args = [
        "run",
        str(PIXELS),
        *[a for kv in TINY for a in ("--set", kv)],
        *("--set", "irl.algorithm=bc", "--set", "irl.demonstrations.expert=2", "--set", "irl.bc.epochs=3"),
        *("--set", "train.warm_start=null"),
    ]
    res = CliRunner().invoke(app, [*args, "--runs", str(tmp_path), "--no-progress"])
    assert res.exit_code == 0, res.output
    run = only_run(tmp_path)
    assert len(list((run / "demos").glob("*.npz"))) == 2
    assert json.loads((run / "meta.json").read_text())["status"] == "done"
    assert "1 file verified" in rrd_verify(run / "recording.rrd")


def test_cloning_loss_falls_on_frames(tmp_path):
    from fastrl.agents.bc import behaviour_clone
    from fastrl.agents.sb3 import build_model, make_vec_env
    from fastrl.data.recordings import load_recordings
    from fastrl.data.replay import demonstration_pairs
    from fastrl.model.scope import joint_ranges
    from fastrl.runner.train.demos import write_demos

    spec = load_spec(PIXELS, ["observation.image.size=32", "train.n_envs=1"])
    write_demos(tmp_path, 2, 0, expert_spec=spec, progress=False)
    named, _ = load_recordings([tmp_path], joint_ranges(spec.scope))
    obs, actions = demonstration_pairs(FastEnv(spec), [t for _, t in named])
    assert obs.shape[1:] == (32, 32, 6) and obs.dtype == np.uint8 and len(obs) == len(actions)
    model = build_model(spec, make_vec_env(spec, 1, 0, workers=1))
    losses = behaviour_clone(model, model.get_env(), obs, actions, epochs=8, batch_size=64, lr=1e-3)
    assert losses[-1] < 0.85 * losses[0] and losses == sorted(losses, reverse=True), losses


def test_image_workers_start_fresh_after_this_process_rendered():
    """A worker forked after this process made an EGL context would hang at its first frame (Mesa)."""
    import signal

    from fastrl.agents.sb3 import make_vec_env

    spec = load_spec(PIXELS, ["observation.image.size=32"])
    FastEnv(spec).reset(seed=0)  # this process now holds a GL context
    venv = make_vec_env(spec, 4, 0, workers=2)

    def stuck(*_):
        raise TimeoutError("a worker did not answer within 120 s")

    old = signal.signal(signal.SIGALRM, stuck)
    signal.alarm(120)
    try:
        obs = venv.reset()
        obs, *_ = venv.step(np.zeros(4, int))
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
        venv.close()
    assert obs.shape == (4, 32, 32, 6) and obs[2:].std() > 0  # the worker's envs rendered


def test_warm_started_pixel_run_logs_its_dagger_rounds(tmp_path):
    warm = ["demonstrations=2", "rounds=2", "episodes=1", "epochs=2", "batch_size=64"]
    args = ["run", str(PIXELS), "--timesteps", "256", *[a for kv in TINY for a in ("--set", kv)]]
    args += [a for kv in warm for a in ("--set", f"train.warm_start.{kv}")]
    res = CliRunner().invoke(app, [*args, "--runs", str(tmp_path), "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "DAgger round 2" in res.output
    run = only_run(tmp_path)
    rows = [json.loads(line) for line in (run / "warm_start.jsonl").read_text().splitlines()]
    assert [r["dagger_round"] for r in rows] == [0, 1, 2]
    assert rows[0]["dagger_subtasks"] > 0  # the expert's own episodes (3 s long here) complete some subtasks
    pairs = [r["dagger_pairs"] for r in rows]
    assert pairs == sorted(pairs) and pairs[0] < pairs[1] and all(np.isfinite(r["dagger_loss"]) for r in rows)
    meta = json.loads((run / "meta.json").read_text())
    assert meta["status"] == "done" and meta["warm_start"]["pairs"] == pairs[-1]
    assert "1 file verified" in rrd_verify(run / "recording.rrd")
    entities, _ = recorded(run / "recording.rrd")
    assert {"/metrics/warm_start/dagger_loss", "/metrics/warm_start/dagger_subtasks"} <= entities


def test_warm_start_is_for_ppo_on_the_specs_reward():
    from fastrl.spec import SpecError

    for overrides in (["train.algo=SAC", "actions.mode=rates"], ["irl.algorithm=bc"]):
        with pytest.raises(SpecError, match="train.warm_start: the warm start is for PPO"):
            load_spec(PIXELS, overrides)


def test_dagger_labels_the_policys_states_with_the_experts_actions():
    from fastrl.agents.dagger import labelled_episodes
    from fastrl.agents.expert import ScriptedExpert

    spec = load_spec(PIXELS, ["observation.image.size=32", "episode.time_limit=2"])
    env = FastEnv(spec)
    expert = ScriptedExpert(env)
    led = labelled_episodes(env, expert, [5])
    still = labelled_episodes(env, expert, [5], act=lambda obs: 0)  # a policy that never moves
    assert len(still.labels) == 40 and still.subtasks == 0.0 and still.obs.shape == (40, 32, 32, 6)
    assert (still.labels != 0).all()  # the expert would move it
    assert np.array_equal(still.obs[0], led.obs[0]) and still.labels[0] == led.labels[0]
    assert not np.array_equal(still.obs[5], led.obs[5])  # the expert's episode moved on
    always = labelled_episodes(env, expert, [5], act=lambda obs: 0, expert_share=1.0)
    assert np.array_equal(always.obs, led.obs) and np.array_equal(always.labels, led.labels)
    half = labelled_episodes(env, expert, [5], act=lambda obs: 0, expert_share=0.5)
    assert not np.array_equal(half.obs[5:10], led.obs[5:10]) and not np.array_equal(half.obs[5:10], still.obs[5:10])
