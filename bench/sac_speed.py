"""How fast SAC trains per update schedule and implementation, alone and as the off-policy AIRL generator.

    python bench/sac_speed.py                      # all schedules, ~6 min on a quiet 2-core machine
    python bench/sac_speed.py --schedules sb3 lean-128-4env-half --steps 4000

Each schedule trains SAC on TraceLines (rates actions), first past learning_starts (not timed), then for
--steps environment steps (timed, best of --rounds). Rows marked AIRL run off-policy AIRL from 20 scripted-expert
demonstrations in the loop (current-rollout sampling, spectral norm, 16 discriminator steps per rollout).
The reference is plain stable-baselines3 SAC with its default schedule (1 env, 1 gradient step per env step,
batch 256, [256, 256]) on the heuristic reward, measured in the same process. The schedules without AIRL are
those of bench/sac_schedules.py, which measures their final performance.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import time

from common import machine_line

SCHEDULES = {
    # name: (n_envs, train_freq per env, gradient_steps, batch, net, lean update, AIRL discriminator in the loop)
    "sb3": (1, 1, 1, 256, [256, 256], False, False),
    "lean": (1, 1, 1, 256, [256, 256], True, False),
    "lean-128": (1, 1, 1, 256, [128, 128], True, False),
    "lean-128-b128": (1, 1, 1, 128, [128, 128], True, False),
    "lean-128-half": (1, 2, 1, 256, [128, 128], True, False),
    "lean-128-4env-half": (4, 1, 2, 256, [128, 128], True, False),
    "lean-128-4env-quarter": (4, 1, 1, 256, [128, 128], True, False),
    "sb3 + AIRL": (1, 1, 1, 256, [256, 256], False, True),
    "8 envs x 32 steps + AIRL": (8, 32, 32, 256, [128, 128], False, True),
    "8 envs x 32 steps, lean + AIRL": (8, 32, 32, 256, [128, 128], True, True),
}


def build(name: str, demos):
    """A SAC model on TraceLines with the schedule, and its callback (or None)."""
    from fastrl.agents.sb3 import build_model, make_vec_env
    from fastrl.irl import (
        Discriminator,
        DiscriminatorFit,
        DiscriminatorForm,
        OffPolicyAdversarialCallback,
        RelabelingReplayBuffer,
    )
    from fastrl.spec import load_spec

    n_envs, freq, grad, batch, net, lean, with_disc = SCHEDULES[name]
    sets = [
        "actions.mode=rates",
        "train.algo=SAC",
        f"train.n_envs={n_envs}",
        f"train.sac.train_freq={freq}",
        f"train.sac.gradient_steps={grad}",
        f"train.sac.batch_size={batch}",
        f"train.sac.net_arch={net}",
        "train.sac.learning_starts=1000",
        f"train.sac.lean_update={str(lean).lower()}",
    ]
    sets += ["irl.algorithm=airl"] if with_disc else []
    spec = load_spec("specs/tracelines.yaml", sets)
    venv = make_vec_env(spec, n_envs, 0)
    model = build_model(spec, venv, replay_buffer_class=RelabelingReplayBuffer if with_disc else None)
    cb = None
    if with_disc:
        disc = Discriminator(venv.observation_space.shape[0], DiscriminatorForm(kind="airl", gamma=0.99, spectral=True))
        cb = OffPolicyAdversarialCallback(DiscriminatorFit(disc, lr=1e-3), demos(spec), current_rollout=True, steps=16)
    return model, cb


def main() -> None:
    """Time every schedule and print the table."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--schedules", nargs="+", default=list(SCHEDULES), choices=list(SCHEDULES))
    ap.add_argument("--steps", type=int, default=3000, help="timed env steps per round (x n_envs/2 for several envs)")
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()

    from fastrl.data.replay import expert_trajectories
    from fastrl.env import FastEnv
    from fastrl.irl.demonstrations import expert_transitions

    cache = {}

    def demos(spec):
        if "t" not in cache:
            cache["t"] = expert_transitions(FastEnv(spec), expert_trajectories(FastEnv(spec), range(20)))
        return cache["t"]

    print(f"# {machine_line()} (models on 1 thread)")
    print("| schedule | envs | steps/update | batch | net | lean | steps/s | ms per update | vs plain SB3 SAC |")
    print("|---|---|---|---|---|---|---|---|---|")
    ref = None
    for name in ["sb3", *[n for n in args.schedules if n != "sb3"]]:  # the reference first
        model, cb = build(name, demos)
        n_envs, freq, grad, batch, net, lean, _ = SCHEDULES[name]
        model.learn(1200, callback=cb)  # past learning_starts
        steps = args.steps * max(1, n_envs // 2)
        best = 0.0
        for _ in range(args.rounds):
            t0 = time.perf_counter()
            model.learn(steps, callback=cb, reset_num_timesteps=False)
            best = max(best, steps / (time.perf_counter() - t0))
        updates_per_step = grad / (freq * n_envs)
        ms = 1e3 / best / updates_per_step
        ref = best if ref is None else ref
        print(
            f"| {name} | {n_envs} | {1 / updates_per_step:g} | {batch} | {net} | {'yes' if lean else 'no'} | "
            f"{best:,.0f} | {ms:.1f} | {best / ref:.1f}x |",
            flush=True,
        )


if __name__ == "__main__":
    main()
