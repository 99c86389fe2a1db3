"""`fastrl run` and `fastrl irl` compile the task's MuJoCo model once, however many stages use it."""

from collections import OrderedDict

import pytest

from fastrl.model import compiler

from ..conftest import spec_file
from .test_irl_runner import GENERATOR, invoke

TINY = ["train.n_envs=2", "train.workers=1", "evaluate.episodes=1", "evaluate.image_every=0", "episode.time_limit=4"]


@pytest.fixture
def builds(monkeypatch) -> list:
    """The specs compiled from here on: an empty compile cache, and the real compiler counting its calls."""
    built = []
    build = compiler.build_task

    def counted(spec):
        built.append(spec.name)
        return build(spec)

    monkeypatch.setattr(compiler, "_COMPILED", OrderedDict())
    monkeypatch.setattr(compiler, "build_task", counted)
    return built


@pytest.mark.parametrize(
    "args",
    [
        ["run", "--timesteps", "128", "--set", "train.ppo.n_steps=64", "--set", "train.ppo.batch_size=64"],
        [
            "irl",
            "--timesteps",
            "128",
            "--set",
            "irl.demonstrations.expert=1",
            *[a for g in GENERATOR for a in ("--set", g)],
        ],
    ],
    ids=["run", "irl"],
)
def test_one_command_compiles_the_task_once(args, builds, tmp_path):
    sets = [a for kv in TINY for a in ("--set", kv)]
    res = invoke([args[0], str(spec_file("tracelines")), *args[1:], *sets], tmp_path)
    assert res.exit_code == 0, res.output
    assert builds == ["tracelines"]
