"""PPO training steps/s of a bundled spec against one core's raw physics and plain SB3 PPO, in one run.

    python bench/ppo_speed.py [--tasks tracelines] [--steps 61440] [--rounds 3] [--json OUT]

Per task, in interleaved rounds (median and best reported):
  physics   raw `mujoco.mj_step(model, data, nstep=substeps)` on the spec's compiled model, one core: what one env
            step costs in physics alone (issue 41's reference);
  fastrl    PPO as `fastrl run` trains it (the spec's envs, workers and hyperparameters: `make_vec_env` and
            `build_model`), timed over --steps after a warm-up update; periodic evaluation and recording left out;
  sb3       stable-baselines3 PPO at its library defaults (MlpPolicy, 1 env, n_steps 2048, 10 epochs) on the same
            FastEnv through SB3's DummyVecEnv: the plain algorithm, the learners' reference.
Prints fastrl's steps/s as a share of the physics steps/s (issue 41 asks >= 0.45) and beside SB3's.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("CI", "1")

import argparse
import json
import statistics
import time
from pathlib import Path

import mujoco
import numpy as np
from common import machine_line  # noqa: E402

from fastrl.agents.sb3 import build_model, make_vec_env  # noqa: E402
from fastrl.env.fast_env import FastEnv  # noqa: E402
from fastrl.spec import load_spec  # noqa: E402


def physics_steps_per_s(spec, steps: int = 20_000) -> float:
    """Env steps/s of raw mj_step (substeps per env step) on the spec's model, from a reset state, random ctrl."""
    env = FastEnv(spec)
    env.reset(seed=0)
    model, data = env.model, mujoco.MjData(env.model)
    mujoco.mj_copyData(data, model, env.data)
    rng = np.random.default_rng(0)
    lo, hi = model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1]
    ctrl = rng.uniform(lo, hi, (64, model.nu)) if model.nu else np.zeros((64, 0))
    t0 = time.perf_counter()
    for k in range(steps):
        data.ctrl[:] = ctrl[k % 64]
        mujoco.mj_step(model, data, nstep=env.substeps)
    env.close()
    return steps / (time.perf_counter() - t0)


def fastrl_ppo_steps_per_s(spec, steps: int) -> float:
    """Training steps/s of the spec's PPO on its vectorised envs, after one warm-up update."""
    venv = make_vec_env(spec, spec.train.n_envs, spec.train.seed, spec.train.workers)
    try:
        model = build_model(spec, venv, seed=spec.train.seed)
        model.learn(model.n_steps * venv.num_envs)
        t0 = time.perf_counter()
        model.learn(steps, reset_num_timesteps=False)
        return steps / (time.perf_counter() - t0)
    finally:
        venv.close()


def sb3_ppo_steps_per_s(spec, steps: int) -> float:
    """Training steps/s of stable-baselines3 PPO at its defaults on one FastEnv of the spec."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env as sb3_vec_env

    venv = sb3_vec_env(lambda: FastEnv(spec), n_envs=1, seed=0)
    try:
        model = PPO("MlpPolicy", venv, seed=0, device="cpu")
        model.learn(model.n_steps)
        t0 = time.perf_counter()
        model.learn(steps, reset_num_timesteps=False)
        return steps / (time.perf_counter() - t0)
    finally:
        venv.close()


def main() -> None:
    """Measure, print and optionally write the JSON."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", nargs="+", default=["tracelines"])
    ap.add_argument("--steps", type=int, default=61_440, help="timed PPO steps per round (fastrl and SB3)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    print(f"machine: {machine_line()}", flush=True)
    results = {"machine": machine_line(), "steps": args.steps, "tasks": {}}
    for task in args.tasks:
        spec = load_spec(task)
        runs = {"physics": [], "fastrl": [], "sb3": []}
        for r in range(args.rounds):
            runs["physics"].append(physics_steps_per_s(spec))
            runs["fastrl"].append(fastrl_ppo_steps_per_s(spec, args.steps))
            runs["sb3"].append(sb3_ppo_steps_per_s(spec, min(args.steps, 16_384)))
            print(f"{task} round {r + 1}: " + ", ".join(f"{k} {v[-1]:,.0f}" for k, v in runs.items()), flush=True)
        med = {k: statistics.median(v) for k, v in runs.items()}
        ratios = [f / p for f, p in zip(runs["fastrl"], runs["physics"], strict=True)]
        results["tasks"][task] = {"steps_per_s": runs, "median": med, "ratio_per_round": ratios}
        print(
            f"{task}: physics {med['physics']:,.0f} env steps/s (one core), fastrl PPO {med['fastrl']:,.0f} "
            f"({spec.train.n_envs} envs, {spec.train.workers} processes), SB3 PPO defaults {med['sb3']:,.0f}; "
            f"fastrl / physics {statistics.median(ratios):.2f} (rounds {', '.join(f'{x:.2f}' for x in ratios)}; "
            f"issue 41 asks >= 0.45), fastrl / SB3 {med['fastrl'] / med['sb3']:.1f}x",
            flush=True,
        )
    print(f"machine after: {machine_line()}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
