"""Behavioural cloning from scripted-expert demonstrations written in the trajectory contract."""

import numpy as np

import fastrl
from fastrl.agents.bc import action_accuracy, behaviour_clone
from fastrl.agents.expert import ScriptedExpert
from fastrl.agents.sb3 import build_model, make_vec_env
from fastrl.data import load_trajectories
from fastrl.data.replay import demonstration_pairs, rollout_trajectory
from fastrl.spec import load_spec

from ..conftest import spec_file


def test_bc_fits_expert_demonstrations_and_bad_files_are_reported(tmp_path):
    spec = load_spec(spec_file("tracelines"))
    env = fastrl.make(spec)
    expert = ScriptedExpert(env)
    for seed in range(6):
        traj, _ = rollout_trajectory(env, expert.act, seed, {"source": "expert"}, expert.reset)
        traj.save(tmp_path / f"demo{seed}.npz")
    (tmp_path / "broken.npz").write_bytes(b"\x00" * 10)
    trajs, errors = load_trajectories([tmp_path])
    assert len(trajs) == 6 and len(errors) == 1 and "broken.npz" in errors[0]
    obs, actions = demonstration_pairs(env, trajs)
    assert len(obs) == len(actions) == sum(len(t.actions) for t in trajs)
    venv = make_vec_env(spec, 1, 0)
    model = build_model(spec, venv)
    before = action_accuracy(model, venv, obs, actions)
    losses = behaviour_clone(model, venv, obs, actions, epochs=40)
    after = action_accuracy(model, venv, obs, actions)
    assert losses[-1] < 0.6 * losses[0]
    assert after > 0.6 and after > before + 0.2
    assert np.isfinite(losses).all()
