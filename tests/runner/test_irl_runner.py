"""`fastrl irl` and `fastrl run` with an irl section, end to end on tiny budgets of the real thing."""

import io
import json
from pathlib import Path

import numpy as np
import pytest
import torch
from rich.console import Console
from safetensors import safe_open
from stable_baselines3.common.callbacks import BaseCallback
from typer.testing import CliRunner

from fastrl.agents.bc import action_accuracy
from fastrl.cli import app
from fastrl.data.replay import demonstration_pairs, replay
from fastrl.data.trajectory import Trajectory
from fastrl.env import FastEnv
from fastrl.irl.export import load_networks
from fastrl.runner.train.learner import build_learner
from fastrl.spec import load_spec

from ..conftest import spec_file
from .test_runner import only_run, recorded, rrd_verify

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

# GAIL and AIRL on PPO learn with irl.generator's settings (the bundled specs have them), apart from train.ppo's
GENERATOR = [
    "irl.generator.n_envs=2",
    "irl.generator.ppo.n_steps=32",
    "irl.generator.ppo.batch_size=64",
    "irl.generator.ppo.n_epochs=1",
    "irl.generator.ppo.net_arch=[24, 24]",
]
TINY = [
    "train.n_envs=2",
    "train.ppo.n_steps=64",
    "train.ppo.batch_size=64",
    "train.ppo.n_epochs=1",
    "train.log_every=128",
    "train.checkpoint_every=256",
    "evaluate.episodes=2",
    "evaluate.record_episodes=1",
    "evaluate.image_every=0",
    "episode.time_limit=8",
    "irl.demonstrations.expert=2",
    "evaluate.periodic_every=256",
    "evaluate.periodic_episodes=1",
    *GENERATOR,
]
SAC = [
    "actions.mode=continuous",
    "train.algo=SAC",
    "train.sac.learning_starts=64",
    "train.sac.batch_size=32",
    "train.sac.train_freq=16",
    "train.sac.gradient_steps=4",
    "train.sac.net_arch=[32, 32]",
    "train.sac.periodic_every=256",  # SAC evaluates on its own cadence (the spec's: every 10k steps)
]


def sets(extra=()):
    """CLI --set arguments."""
    return [a for kv in [*TINY, *extra] for a in ("--set", kv)]


def invoke(args, runs: Path):
    """The CLI, in-process."""
    return CliRunner().invoke(app, [*args, "--runs", str(runs), "--no-progress"])


@pytest.mark.parametrize(
    ("algorithm", "extra", "suffix"),
    [("gail", [], "-gail-ppo-s0"), ("airl", [], "-airl-ppo-s0"), ("airl", SAC, "-airl-sac-s0"), ("bc", [], "-bc-s0")],
)
def test_irl_runs_end_to_end_from_a_spec(tmp_path, algorithm, extra, suffix):
    res = invoke(
        ["irl", str(spec_file("tracelines")), "--algorithm", algorithm, "--timesteps", "512", *sets(extra)], tmp_path
    )
    assert res.exit_code == 0, res.output
    assert ("goes without it" in res.output) is (suffix == "-airl-sac-s0")  # the spec's ranking prior: PPO AIRL's
    run = only_run(tmp_path)
    assert run.name.endswith(suffix)
    metrics = run / "metrics.jsonl"  # BC trains offline and logs none
    assert (metrics.exists() and "irl/ranking_loss" in metrics.read_text()) is (suffix == "-airl-ppo-s0")
    demos = sorted((run / "demos").glob("*.npz"))
    assert len(demos) == 2
    ev = json.loads((run / "eval.json").read_text())
    assert ev["agent"]["episodes"] == 2
    nets = load_networks(run / "networks")
    traj = Trajectory.load(demos[0])
    obs, infos, _ = replay(FastEnv(load_spec(run / "spec.yaml")), traj)
    assert nets.value(obs).shape == (len(obs),) and np.isfinite(nets.value(obs)).all()
    assert len(nets.policy(obs)) == len(obs)
    generator = json.loads((run / "meta.json").read_text()).get("generator")
    with safe_open(str(run / "networks" / "policy.safetensors"), "pt") as f:
        widths = {f.get_slice(k).get_shape()[0] for k in f.keys() if k.endswith("0.weight")}
    if algorithm == "bc":  # BC fits the network a PPO generator starts from, not forward RL's
        assert not (run / "networks" / "reward.safetensors").exists()
        assert generator["source"] == "irl.generator" and widths == {24}
        assert "BC into PPO on 2 envs (irl.generator)" in res.output
        return
    with safe_open(str(run / "networks" / "reward.safetensors"), "pt") as f:
        disc = json.loads(f.metadata()["fastrl"])["discriminator"]
    assert disc["policy_term"] is ("train.algo=SAC" not in extra)  # AIRL on SAC: f alone by default
    if "train.algo=SAC" in extra:  # the generator block is for PPO: SAC learns with train.sac
        assert generator is None and "generator:" not in res.output and 24 not in widths
    else:
        assert generator["source"] == "irl.generator" and generator["n_envs"] == 2
        assert generator["ppo"]["n_steps"] == 32 and generator["ppo"]["net_arch"] == [24, 24]
        assert "generator: PPO on 2 envs (irl.generator)" in res.output and widths == {24}
    rewards = nets.reward(obs)
    assert rewards.shape == (len(obs) - 1,) and np.isfinite(rewards).all()
    late = obs.copy()
    late[:, -1] = 0.9  # the observation's last term is the clock, `elapsed`
    assert np.allclose(nets.reward(late), rewards) is (algorithm == "gail")  # GAIL's reward does not see it
    shown = [replay(FastEnv(load_spec(run / "spec.yaml")), Trajectory.load(d))[0] for d in demos]
    assert nets.reward_ceiling == pytest.approx(max(nets.reward(o).max() for o in shown), abs=1e-5)  # the best shown
    assert nets.value_ceiling == pytest.approx(max(nets.value(o[:-1]).max() for o in shown), abs=1e-5)
    assert np.isfinite(nets.learned_return(obs, terminated=bool(infos[-1]["success"])))
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    keys = set().union(*rows)
    assert {"irl/disc_loss", "irl/disc_accuracy", "irl/reward_expert", "irl/reward_policy", "eval/subtasks"} <= keys
    assert (run / "final" / "parts.pt").exists()
    rrd_verify(run / "recording.rrd")
    entities, _ = recorded(run / "recording.rrd")
    assert any("irl/disc_accuracy" in e for e in entities) and any("eval/subtasks" in e for e in entities)


def test_airl_with_the_ranking_prior_logs_its_loss_and_gail_goes_without_it(tmp_path):
    ranking = [
        "irl.discriminator.ranking=1",
        "irl.discriminator.ranking_noise=[0, 1]",
        "irl.discriminator.ranking_episodes=1",
    ]
    res = invoke(
        ["irl", str(spec_file("tracelines")), "--algorithm", "airl", "--timesteps", "256", *sets(ranking)],
        tmp_path / "airl",
    )
    assert res.exit_code == 0, res.output
    rows = [json.loads(line) for line in (only_run(tmp_path / "airl") / "metrics.jsonl").read_text().splitlines()]
    losses = [r["irl/ranking_loss"] for r in rows if "irl/ranking_loss" in r]
    assert losses and all(np.isfinite(v) and v > 0 for v in losses)
    res = invoke(
        ["irl", str(spec_file("tracelines")), "--algorithm", "gail", "--timesteps", "256", *sets(ranking)],
        tmp_path / "gail",
    )
    assert res.exit_code == 0, res.output
    assert "irl.discriminator.ranking" not in res.output  # the shipped specs set the prior: GAIL goes without a word
    rows = (only_run(tmp_path / "gail") / "metrics.jsonl").read_text()
    assert "irl/ranking_loss" not in rows


def test_irl_reads_a_demo_folder_and_reports_bad_files(tmp_path):
    demos = tmp_path / "demos"
    res = CliRunner().invoke(
        app, ["demos", "--expert", str(spec_file("tracelines")), "-n", "2", "-o", str(demos), "--no-progress"]
    )
    assert res.exit_code == 0, res.output
    (demos / "broken.npz").write_bytes(b"not a trajectory")
    res = invoke(
        ["irl", str(spec_file("tracelines")), "--demos", str(demos), "--timesteps", "256", *sets()], tmp_path / "runs"
    )
    assert res.exit_code == 0, res.output
    assert "broken.npz" in res.output
    run = only_run(tmp_path / "runs")
    assert not (run / "demos").exists()
    assert json.loads((run / "meta.json").read_text())["status"] == "done"


def test_irl_without_usable_demonstrations_is_a_clear_error(tmp_path):
    empty = tmp_path / "none"
    empty.mkdir()
    res = invoke(
        ["irl", str(spec_file("tracelines")), "--demos", str(empty), "--timesteps", "256", *sets()], tmp_path / "runs"
    )
    assert res.exit_code == 2
    assert "no usable demonstrations" in res.output and "Traceback" not in res.output
    res = invoke(["irl", str(spec_file("tracelines")), "--algorithm", "maxent", *sets()], tmp_path / "runs")
    assert res.exit_code == 2 and "irl.algorithm" in res.output


def test_run_with_an_irl_section_resumes_with_its_discriminator(tmp_path):
    res = invoke(["run", str(spec_file("tracelines")), "--timesteps", "256", *sets(["irl.algorithm=airl"])], tmp_path)
    assert res.exit_code == 0, res.output
    run = only_run(tmp_path)
    ckpt = sorted((run / "checkpoints").glob("*/parts.pt"))
    assert ckpt
    res = CliRunner().invoke(app, ["run", "--resume", str(run), "--timesteps", "512", "--no-progress"])
    assert res.exit_code == 0, res.output
    assert json.loads((run / "meta.json").read_text())["trained_timesteps"] >= 512


def test_the_averaged_reward_survives_a_resume_and_leaves_training_as_it_was(tmp_path):
    average = ["irl.algorithm=airl", "irl.discriminator.average_every=128"]  # rollouts of 128 steps
    for name, extra in (("whole", average), ("plain", ["irl.algorithm=airl", "irl.discriminator.average_every=0"])):
        res = invoke(["run", str(spec_file("tracelines")), "--timesteps", "512", *sets(extra)], tmp_path / name)
        assert res.exit_code == 0, res.output
    res = invoke(["run", str(spec_file("tracelines")), "--timesteps", "256", *sets(average)], tmp_path / "resumed")
    assert res.exit_code == 0, res.output
    resumed = only_run(tmp_path / "resumed")
    res = CliRunner().invoke(app, ["run", "--resume", str(resumed), "--timesteps", "512", "--no-progress"])
    assert res.exit_code == 0, res.output
    whole, plain = only_run(tmp_path / "whole"), only_run(tmp_path / "plain")
    # copies at 128, 256 (saved in the checkpoint the resume starts from) and 384; the one at 512 is the final
    assert [load_networks(r / "networks").reward_members for r in (whole, resumed, plain)] == [4, 4, 1]
    agent = [json.loads((r / "eval.json").read_text())["agent"] for r in (whole, plain)]
    assert agent[0] == agent[1]
    nets = {r: load_networks(r / "networks") for r in (whole, plain)}
    traj = Trajectory.load(sorted((whole / "demos").glob("*.npz"))[0])
    obs, _, _ = replay(FastEnv(load_spec(whole / "spec.yaml")), traj)
    np.testing.assert_array_equal(nets[whole].value(obs), nets[plain].value(obs))  # the same generator
    final = load_networks(whole / "networks", averaged=False)
    np.testing.assert_allclose(final.reward(obs), nets[plain].reward(obs), atol=1e-6)  # the same discriminator
    assert not np.allclose(nets[whole].reward(obs), nets[plain].reward(obs), atol=1e-3)


def test_resuming_with_a_discriminator_the_spec_no_longer_builds_is_a_clear_error(tmp_path):
    res = invoke(
        [
            "run",
            str(spec_file("tracelines")),
            "--timesteps",
            "256",
            *sets(["irl.algorithm=gail", "irl.discriminator.ignore=[]"]),
        ],
        tmp_path,
    )
    assert res.exit_code == 0, res.output
    run = only_run(tmp_path)
    spec = (run / "spec.yaml").read_text()
    assert "\n    ignore: []" in spec
    (run / "spec.yaml").write_text(spec.replace("\n    ignore: []", "\n    ignore: null"))  # GAIL's default: no clock
    res = CliRunner().invoke(app, ["run", "--resume", str(run), "--timesteps", "512", "--no-progress"])
    assert res.exit_code == 2 and "parts.pt" in res.output and "does not fit" in res.output, res.output
    assert res.exception is None or isinstance(res.exception, SystemExit)
    assert (run / "recording.rrd").exists() and not list(run.glob("recording.part*.rrd"))  # nothing moved


@pytest.mark.parametrize("algorithm", ["none", "airl"])
def test_gail_airl_learn_with_irl_generator_and_forward_rl_with_train(tmp_path, algorithm):
    spec = load_spec(
        spec_file("tracelines"),
        [*TINY, f"irl.algorithm={algorithm}", "irl.discriminator.ranking=0", "irl.generator.ppo.learning_rate=5e-4"],
    )
    learner = build_learner(spec, tmp_path, Console(file=io.StringIO()), progress=False)
    try:
        model = learner.model
        want = (spec.irl.generator.ppo, spec.irl.generator.n_envs) if algorithm == "airl" else (spec.train.ppo, 2)
        ppo, n_envs = want
        assert (model.n_envs, model.n_steps, model.batch_size, model.n_epochs) == (
            n_envs,
            ppo.n_steps,
            ppo.batch_size,
            ppo.n_epochs,
        )
        assert model.learning_rate == ppo.learning_rate and model.policy.net_arch["pi"] == ppo.net_arch
        assert (spec.train.ppo.n_steps, spec.irl.generator.ppo.n_steps) == (64, 32)  # the two really differ
    finally:
        learner.venv.close()


def test_a_cloned_generator_starts_from_the_demonstrations_behaviour(tmp_path):
    base = [*TINY, "irl.algorithm=airl", "irl.discriminator.ranking=0", "irl.demonstrations.expert=4"]
    accuracy = {}
    for cloned in (False, True):
        spec = load_spec(spec_file("tracelines"), [*base, f"irl.generator.cloned={str(cloned).lower()}"])
        assert spec.cloned_generator is cloned
        (tmp_path / str(cloned)).mkdir()
        learner = build_learner(spec, tmp_path / str(cloned), Console(file=io.StringIO()), progress=False)
        try:
            pairs = demonstration_pairs(FastEnv(spec), learner.demos)
            if cloned:
                learner.clone()
                assert learner.venv.training is False  # the clone's normalisation stays through adversarial training
                np.testing.assert_allclose(learner.venv.obs_rms.mean, pairs[0].mean(axis=0), rtol=1e-5, atol=1e-6)
            accuracy[cloned] = action_accuracy(learner.model, learner.venv, *pairs)
        finally:
            learner.venv.close()
    assert accuracy[True] > accuracy[False] + 0.25  # 11 discrete actions: an untrained policy matches by chance


def test_irl_with_a_cloned_generator_says_so_keeps_it_in_meta_and_resumes_as_it_ran(tmp_path):
    cloned = ["irl.discriminator.ranking=0", "irl.generator.cloned=true"]
    args = ["irl", str(spec_file("tracelines")), "--algorithm", "airl"]
    res = invoke([*args, "--timesteps", "512", *sets(cloned)], tmp_path / "whole")
    assert res.exit_code == 0, res.output
    assert "generator: cloned from 2 demonstrations, action accuracy" in res.output
    whole = only_run(tmp_path / "whole")
    assert json.loads((whole / "meta.json").read_text())["generator"]["cloned"] is True
    res = invoke([*args, "--timesteps", "256", *sets(cloned)], tmp_path / "resumed")
    assert res.exit_code == 0, res.output
    resumed = only_run(tmp_path / "resumed")
    res = CliRunner().invoke(app, ["run", "--resume", str(resumed), "--timesteps", "512", "--no-progress"])
    assert res.exit_code == 0 and "cloned from" not in res.output, res.output  # cloned once, at step 0
    stats = [np.load(r / "final" / "normalize.npz") for r in (whole, resumed)]  # the clone's, never updated:
    for key in ("obs_mean", "obs_var", "obs_count"):  # the resumed run keeps them fixed too
        np.testing.assert_array_equal(stats[0][key], stats[1][key])
    pairs = sum(len(Trajectory.load(f).time) - 1 for f in (whole / "demos").glob("*.npz"))
    assert float(stats[0]["obs_count"]) == pairs


def test_late_starts_reach_the_generator_alone_and_are_kept_in_meta(tmp_path):
    late = ["irl.discriminator.ranking=0", "irl.generator.late_starts=0.5"]
    spec = load_spec(spec_file("tracelines"), [*TINY, "irl.algorithm=airl", *late])
    assert spec.generator_late_starts == 0.5
    assert load_spec(spec_file("tracelines"), [*TINY, *late]).generator_late_starts == 0.0  # forward RL
    res = invoke(
        ["irl", str(spec_file("tracelines")), "--algorithm", "gail", "--timesteps", "256", *sets(late)], tmp_path
    )
    assert res.exit_code == 0, res.output
    assert "up to 50% of the time limit late (irl.generator.late_starts)" in res.output
    assert json.loads((only_run(tmp_path) / "meta.json").read_text())["generator"]["late_starts"] == 0.5


class _Quiet(BaseCallback):
    """A monitor that records nothing."""

    def _on_step(self) -> bool:
        return True


def test_an_anchored_generator_stays_nearer_the_demonstrations(tmp_path):
    extra = ["irl.algorithm=airl", "irl.discriminator.ranking=0", "irl.generator.cloned=true"]
    likelihood = {}
    for anchor in (0, 64):
        spec = load_spec(spec_file("tracelines"), [*TINY, *extra, f"irl.generator.anchor={anchor}"])
        (tmp_path / str(anchor)).mkdir()
        learner = build_learner(spec, tmp_path / str(anchor), Console(file=io.StringIO()), progress=False)
        try:
            learner.learn(256, _Quiet())  # the clone, four PPO updates, the anchor's steps between them
            obs, actions = demonstration_pairs(FastEnv(spec), learner.demos)
            x = torch.as_tensor(learner.venv.normalize_obs(obs), dtype=torch.float32)
            with torch.no_grad():
                _, log_prob, _ = learner.model.policy.evaluate_actions(x, torch.as_tensor(actions))
            likelihood[anchor] = float(log_prob.mean())  # of the demonstrated actions under the generator's policy
        finally:
            learner.venv.close()
    assert likelihood[64] > likelihood[0] + 0.2, likelihood
