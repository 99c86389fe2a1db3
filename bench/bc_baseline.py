"""Behavioural cloning from scripted-expert demonstrations: accuracy, training time, evaluation.

The policy network is BC's (`irl.algorithm: bc`): `irl.generator`'s, the one a cloned generator starts from.

python bench/bc_baseline.py [--spec specs/tracelines.yaml] [--demos 20] [--epochs 30]
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import time

from fastrl.agents.bc import action_accuracy, behaviour_clone
from fastrl.agents.sb3 import build_model, make_vec_env, policy_function
from fastrl.data.replay import demonstration_pairs, expert_trajectories
from fastrl.env import FastEnv
from fastrl.runner.train.evaluate import evaluate
from fastrl.spec import load_spec


def main() -> None:
    """Demonstrate, clone, evaluate."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spec", default="specs/tracelines.yaml")
    ap.add_argument("--demos", type=int, default=20)
    ap.add_argument("--epochs", type=int, default=30)
    args = ap.parse_args()
    spec = load_spec(args.spec, ["irl.algorithm=bc"])
    trajs = expert_trajectories(FastEnv(spec), range(args.demos))
    obs, actions = demonstration_pairs(FastEnv(spec), trajs)
    venv = make_vec_env(spec, 1, 0)
    model = build_model(spec, venv)
    t0 = time.perf_counter()
    losses = behaviour_clone(model, venv, obs, actions, epochs=args.epochs)
    seconds = time.perf_counter() - t0
    summary, _ = evaluate(FastEnv(spec), policy_function(model, venv), list(range(10000, 10020)))
    print(
        f"{spec.name}: {args.demos} demos, {len(obs)} pairs, {args.epochs} epochs in {seconds:.1f} s, "
        f"loss {losses[0]:.2f} -> {losses[-1]:.2f}, action accuracy {action_accuracy(model, venv, obs, actions):.2f}"
    )
    print(
        f"evaluation on 20 seeds: success {summary['success_rate']:.0%}, "
        f"subtasks {summary['subtasks_completed']:.1%}, episode time {summary['episode_time_mean']:.1f} s"
    )


if __name__ == "__main__":
    main()
