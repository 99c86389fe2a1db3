"""Envs split across worker processes: the same trajectories and weights as in one process, clean stops."""

import gc
import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import psutil
import torch

from fastrl.agents import lanes
from fastrl.agents.sb3 import batch_policy, build_model, make_vec_env
from fastrl.agents.workers import FreshInfoVecEnv, SplitVecEnv, recv_soon
from fastrl.env.fast_env import FastEnv
from fastrl.runner.train.evaluate import evaluate, evaluate_batched
from fastrl.spec import load_spec

from ..conftest import spec_file

TINY = ["train.n_envs=3", "train.ppo.n_steps=64", "train.ppo.batch_size=96", "train.ppo.n_epochs=2"]


def rollout(venv, steps: int, seed: int) -> list:
    """Observations, rewards, dones and every env's features over random actions."""
    rng = np.random.default_rng(seed)
    out = [venv.reset()]
    for _ in range(steps):
        obs, rewards, dones, infos = venv.step(rng.integers(0, 11, venv.num_envs))
        out += [obs, rewards, dones, [sorted(i["features"].items()) for i in infos]]
        out += [[i["terminal_observation"] for i in infos if "terminal_observation" in i]]
    return out


def test_split_env_steps_exactly_as_the_in_process_one():
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=2"])  # 40 steps: resets inside the rollout
    single = make_vec_env(spec, 5, 7, workers=1)
    split = make_vec_env(spec, 5, 7, workers=2)
    try:
        assert isinstance(single.venv, FreshInfoVecEnv) and isinstance(split.venv, SplitVecEnv)
        assert len(split.venv.procs) == 1 and split.venv.batches == [3, 2]
        a, b = rollout(single, 120, 0), rollout(split, 120, 0)
        assert len(a) == len(b)
        for x, y in zip(a, b):
            if isinstance(x, np.ndarray):
                np.testing.assert_array_equal(x, y)
            else:
                assert str(x) == str(y)
        q = single.env_method("portal_coordinates", indices=[1, 4])
        np.testing.assert_array_equal(np.stack(q), np.stack(split.env_method("portal_coordinates", indices=[1, 4])))
        assert split.get_attr("dt") == single.get_attr("dt") and len(split.get_attr("dt", [3])) == 1
    finally:
        single.close()
        split.close()
    assert not any(p.is_alive() for p in split.venv.procs)


def test_infos_too_large_for_shared_memory_come_by_the_pipe_with_the_same_steps(monkeypatch):
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=2"])
    single = make_vec_env(spec, 4, 3, workers=1)
    monkeypatch.setattr(lanes, "INFO_BYTES", 64)  # before the fork: the worker's infos never fit
    split = make_vec_env(spec, 4, 3, workers=2)
    try:
        assert split.venv.lanes and split.venv.lanes[0].info.size == 64
        for x, y in zip(rollout(single, 60, 1), rollout(split, 60, 1)):
            assert str(x) == str(y)
    finally:
        single.close()
        split.close()


ORPHAN = """
import os, signal, sys
import numpy as np
from fastrl.agents.sb3 import make_vec_env
from fastrl.spec import load_spec
venv = make_vec_env(load_spec(sys.argv[1]), 4, 0, workers=2)
venv.reset()
venv.step(np.zeros(4, np.int64))
print(venv.venv.procs[0].pid, flush=True)
os.kill(os.getpid(), signal.SIGKILL)  # no close, no pipe end closed by an exit handler
"""


def test_a_worker_ends_soon_after_its_parent_is_killed():
    res = subprocess.run([sys.executable, "-c", ORPHAN, str(spec_file("tracelines"))], capture_output=True, text=True)
    assert res.returncode == -signal.SIGKILL, res.stderr
    worker = int(res.stdout.split()[-1])
    deadline = time.time() + 5
    while not gone(worker):
        assert time.time() < deadline, "the env worker outlived its parent"
        time.sleep(0.05)


def gone(pid: int) -> bool:
    """Whether a process has exited (a zombie counts: nothing of it runs)."""
    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


def test_a_worker_ends_once_its_env_is_dropped_unclosed():
    venv = make_vec_env(load_spec(spec_file("tracelines")), 4, 0, workers=2)
    venv.reset()
    (worker,) = venv.venv.procs
    del venv
    gc.collect()  # the pipe's end here closes with it
    worker.join(timeout=5)
    alive = worker.is_alive()
    if alive:
        worker.kill()  # else this test process would wait for it at exit
    assert not alive, "the env worker outlived the env it served"


def trained_weights(workers: int) -> tuple[dict, dict]:
    """PPO weights before and after a few rollouts on envs stepped by `workers` processes."""
    spec = load_spec(spec_file("imagecentring"), [*TINY, f"train.workers={workers}"])
    venv = make_vec_env(spec, spec.train.n_envs, spec.train.seed, spec.train.workers)
    model = build_model(spec, venv)
    before = {k: v.clone() for k, v in model.policy.state_dict().items()}
    model.learn(64 * 3 * 3)
    venv.close()
    return before, model.policy.state_dict()


def test_training_with_worker_processes_gives_the_same_weights():
    (start, one), (_, two) = trained_weights(1), trained_weights(2)
    assert one.keys() == two.keys()
    assert all(torch.equal(one[k], two[k]) for k in one)
    assert not all(torch.equal(one[k], start[k]) for k in one)  # it did train


def test_batched_periodic_evaluation_matches_episode_by_episode():
    spec = load_spec(spec_file("tracelines"), ["episode.time_limit=6"])
    venv = make_vec_env(spec, 1, 0, workers=1)
    model = build_model(spec, venv)
    seeds = [10_000, 10_001, 10_002]
    act = batch_policy(model, venv)
    batched = evaluate_batched([FastEnv(spec) for _ in seeds], act, seeds)
    one_by_one, _ = evaluate(FastEnv(spec), lambda o: act(o[None])[0], seeds)
    for key in ("success_rate", "subtasks_completed", "episode_time_mean"):
        assert batched[key] == one_by_one[key]
    assert np.isclose(batched["return_mean"], one_by_one["return_mean"], rtol=1e-6, atol=1e-6)
    assert batched["episode_time_mean"] > 0


def test_ctrl_c_with_workers_leaves_a_checkpoint_and_no_worker_behind(tmp_path):
    runs = tmp_path / "runs"
    sets = [*TINY, "train.workers=2", "train.checkpoint_every=192", "evaluate.episodes=1", "evaluate.image_every=0"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "fastrl.cli", "run", str(spec_file("tracelines")), "--timesteps", "100000"]
        + [a for kv in sets for a in ("--set", kv)]
        + ["--runs", str(runs), "--no-progress"],
        cwd=tmp_path,
        env={**os.environ, "CI": "1", "MUJOCO_GL": "egl"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, which a terminal's Ctrl-C reaches as a whole
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.time() + 120
    while not list(runs.glob("*/*/checkpoints/[0-9]*/state.json")):
        assert proc.poll() is None, proc.communicate()
        assert time.time() < deadline
        time.sleep(0.1)
    workers = psutil.Process(proc.pid).children()
    idle = [w for w in workers if os.sched_getscheduler(w.pid) == os.SCHED_IDLE]
    assert len(workers) - len(idle) == 1  # one env worker beside the main process on two or more CPUs
    assert len(idle) <= 1  # and the scripted expert's evaluation on the CPU time training leaves, till it is done
    os.killpg(proc.pid, signal.SIGINT)  # the main process and its worker alike
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "Traceback" not in err, err
    run = next(runs.glob("*/*"))
    meta = json.loads((run / "meta.json").read_text())
    saved = json.loads((run / "checkpoints" / f"{meta['trained_timesteps']:010d}" / "state.json").read_text())
    assert meta["status"] == "interrupted" and saved["timesteps"] == meta["trained_timesteps"] > 0
    psutil.wait_procs(workers, timeout=10)
    assert not any(w.is_running() and w.status() != psutil.STATUS_ZOMBIE for w in workers)


def test_recv_soon_waits_past_its_spin_for_a_late_message():
    a, b = mp.Pipe()
    threading.Timer(0.05, lambda: b.send(("step", 7))).start()
    t0 = time.perf_counter()
    assert recv_soon(a, spin=0.002) == ("step", 7) and time.perf_counter() - t0 >= 0.045
    b.send("ready")
    assert recv_soon(a) == "ready"
