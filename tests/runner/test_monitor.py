"""The training monitor: evaluations during training, early stop, extra statistics, checkpoint parts."""

import json

import torch

from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.runner.train.monitor import (
    Checkpoints,
    CurvePoints,
    EpisodeTally,
    PeriodicEvaluation,
    ProgressBar,
    StopAtSubtasks,
    TrainingMonitor,
)
from fastrl.spec import load_spec
from fastrl.spec.irl import min_steps, stop_at_subtasks

from ..conftest import spec_file

TINY = ["train.n_envs=2", "train.ppo.n_steps=32", "train.ppo.batch_size=64", "train.ppo.n_epochs=1"]


class Counter(torch.nn.Module):
    """A stand-in trainable part with a state dict."""

    def __init__(self):
        super().__init__()
        self.w = torch.nn.Parameter(torch.tensor([3.0]))


def test_evaluations_during_training_are_logged_and_can_stop_it(tmp_path):
    spec = load_spec(spec_file("tracelines"), TINY)
    venv = make_vec_env(spec, 2, 0)
    model = build_model(spec, venv)
    scores = iter([0.2, 0.5, 0.95, 1.0])
    calls = []

    def evaluator():
        calls.append(model.num_timesteps)
        return {"eval/subtasks": next(scores)}

    part = Counter()
    tally = EpisodeTally(feature_names=list(spec.reward.features))
    evaluation = PeriodicEvaluation(evaluator=evaluator, every=128)
    points = CurvePoints(
        run=tmp_path, tally=tally, log_every=10_000, evaluation=evaluation, stats=lambda: {"irl/disc_accuracy": 0.75}
    )
    checkpoints = Checkpoints(run=tmp_path, every=192, tally=tally, parts={"disc": part})
    stop = StopAtSubtasks(evaluation=evaluation, at=0.9)
    bar = ProgressBar(total=4096, enabled=False)
    monitor = TrainingMonitor([tally, bar, evaluation, points, checkpoints, stop])
    model.learn(4096, callback=monitor)
    assert monitor.stopped_early and len(calls) == 3 and model.num_timesteps < 4096
    rows = [json.loads(line) for line in (tmp_path / "metrics.jsonl").read_text().splitlines()]
    assert [r["eval/subtasks"] for r in rows] == [0.2, 0.5, 0.95]  # an evaluation makes a point of its own
    assert all(r["irl/disc_accuracy"] == 0.75 for r in rows)
    saved = sorted((tmp_path / "checkpoints").glob("*/parts.pt"))
    assert saved and torch.load(saved[0], weights_only=True)["disc"]["w"].item() == 3.0


def test_no_stop_before_the_generators_least_steps(tmp_path):
    spec = load_spec(spec_file("tracelines"), TINY)
    model = build_model(spec, make_vec_env(spec, 2, 0))
    calls = []

    def evaluator():
        calls.append(model.num_timesteps)
        return {"eval/subtasks": 1.0}  # every evaluation would stop it

    evaluation = PeriodicEvaluation(evaluator=evaluator, every=128)
    stop = StopAtSubtasks(evaluation=evaluation, at=0.9, after=512)
    monitor = TrainingMonitor([EpisodeTally(feature_names=list(spec.reward.features)), evaluation, stop])
    model.learn(4096, callback=monitor)
    assert monitor.stopped_early and 512 <= model.num_timesteps < 4096
    assert calls[0] < 512  # an evaluation came earlier and did not stop it
    shipped = load_spec(spec_file("tracelines"), ["irl.algorithm=airl"])
    assert min_steps(shipped.train, shipped.irl) == 200_000 and min_steps(spec.train, spec.irl) == 0


def test_the_generator_stops_at_its_own_share_of_subtasks_and_forward_rl_at_the_evaluations():
    def stop_at(*overrides):
        spec = load_spec(spec_file("tracelines"), list(overrides))
        return stop_at_subtasks(spec.train, spec.irl, spec.evaluate.stop_at_subtasks)

    assert stop_at() == 0.95  # forward RL: evaluate.stop_at_subtasks
    assert stop_at("irl.algorithm=airl") == 0.9 and stop_at("irl.algorithm=gail") == 0.9  # the PPO generator's own
    assert stop_at("irl.algorithm=airl", "irl.generator.stop_at_subtasks=null") == 0.95
    assert stop_at("irl.algorithm=airl", "evaluate.stop_at_subtasks=null") == 0.9
    assert stop_at("irl.algorithm=airl", "train.algo=SAC", "actions.mode=rates") == 0.95  # no PPO generator
