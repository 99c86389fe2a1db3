"""A policy cloned from recordings, to roll out with injected noise for the ranking prior (D-REX) instead of the
scripted expert."""

from __future__ import annotations

import warnings

from ...agents.bc import behaviour_clone
from ...agents.sb3 import batch_policy, build_model, make_vec_env, policy_function
from ...data.replay import demonstration_pairs
from ...data.trajectory import Trajectory
from ...env.fast_env import FastEnv
from ...spec.models import TaskSpec


class ClonedActor:
    """`act(obs)` of the deterministic cloned policy, `act_batch(observations)` of many at once; `reset()` does
    nothing (the policy keeps no state)."""

    def __init__(self, act, act_batch):
        self.act, self.act_batch = act, act_batch

    def reset(self) -> None:
        """Nothing to forget between episodes."""


def cloned_actor(spec: TaskSpec, demos: list[Trajectory]) -> ClonedActor:
    """Behavioural cloning (the spec's `irl.bc` settings, PPO's policy network) of demonstrations with actions."""
    bc = spec.irl.bc
    venv = make_vec_env(spec, 1, spec.train.seed)  # the ranking prior is for PPO generators: a PPO policy
    with warnings.catch_warnings():  # PPO's batch-size advice for one env: this model is only fitted offline
        warnings.simplefilter("ignore", UserWarning)
        model = build_model(spec, venv)
    obs, actions = demonstration_pairs(FastEnv(spec), demos)
    behaviour_clone(model, venv, obs, actions, bc.epochs, bc.batch_size, bc.learning_rate, spec.train.seed)
    return ClonedActor(policy_function(model, venv), batch_policy(model, venv))
