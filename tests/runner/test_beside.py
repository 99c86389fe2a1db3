"""Work beside this process: a forked child's result, its errors, and the expert evaluated beside the agent."""

import os
import signal
import time

import numpy as np
import pytest

from fastrl.runner.train.beside import Beside, ChildFailed
from fastrl.runner.train.evaluation import evaluate_run
from fastrl.spec import load_spec


def test_result_comes_from_a_child_process():
    assert Beside(os.getpid).result() != os.getpid()
    assert Beside(os.getpid, fork=False).result() == os.getpid()


def test_an_exception_in_the_child_is_raised_here():
    def broken():
        raise ValueError("no such avatar")

    with pytest.raises(ValueError, match="no such avatar"):
        Beside(broken).result()


def test_a_killed_child_is_reported():
    job = Beside(lambda: time.sleep(30))
    os.kill(job.child.pid, signal.SIGKILL)
    with pytest.raises(ChildFailed):
        job.result()


def test_cancel_stops_the_child():
    job = Beside(lambda: time.sleep(30))
    child = job.child
    job.cancel()
    assert not child.is_alive()


def random_policy(spec, seed=0):
    """Uniform discrete actions from a fixed generator (the same sequence for every call of this function)."""
    rng, n = np.random.default_rng(seed), {"tracelines": 11, "triangulation": 19}[spec.name]
    return lambda obs: int(rng.integers(0, n))


@pytest.mark.parametrize("name", ["tracelines", "triangulation"])
def test_expert_beside_the_agent_scores_as_inline(name):
    overrides = ["evaluate.episodes=3", "evaluate.record_episodes=0"]
    inline = load_spec(f"specs/{name}.yaml", [*overrides, "train.workers=1"])
    forked = load_spec(f"specs/{name}.yaml", [*overrides, "train.workers=2"])
    a = evaluate_run(inline, random_policy(inline), None, None)
    b = evaluate_run(forked, random_policy(forked), None, None)
    assert a["expert"] == b["expert"] and a["agent"] == b["agent"]
    assert a["expert"]["subtasks_completed"] == 1.0 > a["agent"]["subtasks_completed"]
