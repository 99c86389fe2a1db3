"""Preview of on-policy adversarial IRL (PPO generator) from scripted-expert demonstrations.

    python bench/irl_preview.py airl 500000 [--spec specs/tracelines.yaml] [--demos 20]

Writes nothing; prints, every 100k steps, the deterministic evaluation on 10 seeds (success rate,
subtasks completed) and the discriminator's statistics. The full `irl` stage (spec section, CLI,
off-policy variants, reward/value export) is issue 4's work; this measures the core loop.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import time

from fastrl.agents.expert import ScriptedExpert
from fastrl.agents.sb3 import build_model, make_vec_env, policy_function
from fastrl.data.replay import expert_transitions, rollout_trajectory
from fastrl.env import FastEnv
from fastrl.irl import AdversarialCallback, Discriminator
from fastrl.runner.evaluate import evaluate
from fastrl.spec import load_spec


def main() -> None:
    """Train and report."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("kind", choices=["gail", "airl"])
    ap.add_argument("timesteps", type=int)
    ap.add_argument("--spec", default="specs/tracelines.yaml")
    ap.add_argument("--demos", type=int, default=20)
    ap.add_argument("--no-entropy", action="store_true", help="AIRL: generator reward f without -log pi")
    args = ap.parse_args()
    spec = load_spec(args.spec, ["train.normalize.reward=false"])
    env = FastEnv(spec)
    expert = ScriptedExpert(env)
    trajs = [rollout_trajectory(env, expert.act, s, {"source": "expert"}, expert.reset)[0] for s in range(args.demos)]
    transitions = expert_transitions(FastEnv(spec), trajs)
    venv = make_vec_env(spec, spec.train.n_envs, spec.train.seed)
    model = build_model(spec, venv)
    callback = AdversarialCallback(Discriminator(env.observation_space.shape[0], args.kind, 0.99), transitions,
                                   entropy=not args.no_entropy)
    t0 = time.perf_counter()
    while model.num_timesteps < args.timesteps:
        model.learn(100_000, callback=callback, reset_num_timesteps=False)
        venv.training = False
        summary, _ = evaluate(FastEnv(spec), policy_function(model, venv), list(range(10000, 10010)))
        venv.training = True
        print(f"{args.kind} {model.num_timesteps} steps {time.perf_counter() - t0:.0f} s  success "
              f"{summary['success_rate']:.0%}  subtasks {summary['subtasks_completed']:.1%}  "
              f"disc accuracy {callback.stats['irl/disc_accuracy']:.2f}", flush=True)


if __name__ == "__main__":
    main()
