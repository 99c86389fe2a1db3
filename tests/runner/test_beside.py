"""Work beside this process: a forked child's result, its errors, and the expert evaluated beside the agent."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.agents.workers import SPIN
from fastrl.forked import idle_work_running
from fastrl.runner.train import evaluation, monitoring
from fastrl.runner.train.beside import Beside, ChildFailed
from fastrl.runner.train.evaluation import evaluate_run
from fastrl.spec import load_spec


def test_result_comes_from_a_child_process():
    assert Beside(os.getpid).result() != os.getpid()
    assert Beside(os.getpid, fork=False).result() == os.getpid()


def test_an_idle_child_yields_the_cpu_and_says_when_it_is_done():
    job = Beside(lambda: os.sched_getscheduler(0), idle=True)
    deadline = time.monotonic() + 30
    while not job.done() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert job.done() and job.result() == os.SCHED_IDLE
    mine = os.sched_getscheduler(0)
    assert Beside(lambda: os.sched_getscheduler(0)).result() == mine != os.SCHED_IDLE  # a plain child keeps this one's
    assert not Beside(os.getpid, fork=False).done()  # computed here, when result() asks


def test_env_workers_leave_the_cpu_they_would_poll_away_to_idle_work_beside():
    spec = load_spec("tracelines")
    busy = Beside(lambda: time.sleep(5))  # at the usual priority: not counted
    quick = Beside(lambda: 1, idle=True)
    assert quick.result() == 1 and not idle_work_running()  # done: its CPU time is no longer wanted
    job = Beside(lambda: time.sleep(5), idle=True)
    assert idle_work_running()
    venvs = [make_vec_env(spec, 2, 0, workers=2)]
    job.cancel()
    assert not idle_work_running()
    venvs.append(make_vec_env(spec, 2, 0, workers=2))
    busy.cancel()
    try:
        assert [v.venv.spin for v in venvs] == [0.0, SPIN] and SPIN > 0
    finally:
        for v in venvs:
            v.close()


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


def test_a_large_result_comes_whole_and_leaves_no_file_behind():
    job = Beside(lambda: np.arange(3_000_000, dtype=np.float64))  # 24 MB: through a file, not the pool's pipe
    path = Path(job.path)
    assert np.array_equal(job.result(), np.arange(3_000_000, dtype=np.float64)) and not path.exists()
    stopped = Beside(lambda: time.sleep(30))
    stopped.cancel()
    assert not Path(stopped.path).exists()


def test_cancel_stops_the_child():
    job = Beside(lambda: time.sleep(30))
    child = job.child
    job.cancel()
    assert not child.is_alive()


def scattered_policy(spec):
    """Discrete actions scattered over the action space, a pure function of the observation (as a trained
    policy's most likely action is): the same in any process."""
    n = {"tracelines": 11, "triangulation": 19}[spec.name]
    return lambda obs: int(abs(float(np.asarray(obs, np.float64).sum())) * 1e4) % n


@pytest.mark.parametrize("name", ["tracelines", "triangulation"])
def test_expert_beside_the_agent_scores_as_inline(name, tmp_path, monkeypatch):
    overrides = ["evaluate.episodes=3", "evaluate.record_episodes=0"]
    inline = load_spec(f"specs/{name}.yaml", [*overrides, "train.workers=1"])
    forked = load_spec(f"specs/{name}.yaml", [*overrides, "train.workers=2"])
    monkeypatch.setenv("FASTRL_CACHE", str(tmp_path / "inline"))  # each computes the expert's evaluation
    a = evaluate_run(inline, scattered_policy(inline), None, None)
    monkeypatch.setenv("FASTRL_CACHE", str(tmp_path / "forked"))
    b = evaluate_run(forked, scattered_policy(forked), None, None)
    assert a["expert"] == b["expert"] and a["agent"] == b["agent"]
    assert a["expert"]["subtasks_completed"] == 1.0 > a["agent"]["subtasks_completed"]


SPLIT_EVALUATION = """
import json
import numpy as np
from fastrl.env.render import rendered_here
from fastrl.runner.train.evaluation import evaluate_run
from fastrl.spec import load_spec

class Logged:
    def __init__(self):
        self.episodes = {}
    def log_episode(self, i, ep, *rest):
        self.episodes[i] = ep

def policy(obs):
    return int(abs(float(np.asarray(obs, np.float64).sum())) * 1e4) % 11

runs = {}
assert not rendered_here()  # so the later half of the episodes runs in a forked child, which renders its images
for workers in (2, 1):
    overrides = ["evaluate.episodes=4", "evaluate.record_episodes=3", "evaluate.expert=false"]
    overrides.append(f"train.workers={workers}")
    logged = Logged()
    result = evaluate_run(load_spec("specs/tracelines.yaml", overrides), policy, logged, None)
    runs[workers] = (result["agent"], logged.episodes)
(split, a), (inline, b) = runs[2], runs[1]
same = sorted(a) == sorted(b) == [0, 1, 2] and all(
    np.array_equal(a[i].portal, b[i].portal) and sorted(a[i].images) == sorted(b[i].images)
    and all(np.array_equal(a[i].images[k], b[i].images[k]) for k in a[i].images)
    for i in a
)
print(json.dumps({"summaries": split == inline, "records": same, "images": len(a[2].images)}))
"""


def test_a_split_evaluation_gives_the_episodes_and_images_of_one_process():
    res = subprocess.run([sys.executable, "-c", SPLIT_EVALUATION], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out == {"summaries": True, "records": True, "images": out["images"]} and out["images"] > 5


def test_the_periodic_evaluation_splits_across_two_processes_with_the_same_figures(monkeypatch):
    started = []

    class Counted(Beside):
        def __init__(self, fn, **kwargs):
            started.append(os.getpid())
            super().__init__(fn, **kwargs)

    monkeypatch.setattr(monitoring, "Beside", Counted)
    monkeypatch.setattr(evaluation, "rendered_here", lambda: False)  # an earlier test in this process may have
    # rendered; these episodes render nothing, so the child may fork
    figures = []
    for workers, idle_beside in ((1, False), (2, False), (2, True)):
        monkeypatch.setattr(monitoring, "idle_work_running", lambda idle=idle_beside: idle)
        spec = load_spec("tracelines", [f"train.workers={workers}", "evaluate.periodic_episodes=5"])
        venv = make_vec_env(spec, 2, 0)
        model = build_model(spec, venv, seed=3)
        figures.append(monitoring.periodic_evaluator(spec, model, venv)())
        venv.close()
    assert started == [os.getpid()]  # one child: two processes, nothing at the lowest priority beside them
    assert figures[0] == figures[1] == figures[2] and 0 < figures[0]["eval/episode_time"] <= 30
