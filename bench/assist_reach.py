"""Do path suggestions reach the next avatar? Share over states of expert and degraded trajectories, and cost.

    python bench/assist_reach.py RUN_DIR [--episodes 5] [--every 10] [--horizon 3] [--epsilon 0.3 0.7]

The live env follows the scripted expert (and degraded experts: a uniformly random action with probability
epsilon) on held-out seeds 30000, 30001, ...; every `every` steps the run's policy (networks/, plain torch) is
rolled out for `horizon` seconds in a scratch copy from the live state. A suggestion "reaches" when the
policy completes the current subtask (the next avatar appears) within the horizon. Writes JSON next to --out.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
from pathlib import Path

import numpy as np
from common import machine_line

from fastrl.agents.expert import ScriptedExpert
from fastrl.assist import Suggester
from fastrl.env import FastEnv
from fastrl.irl.networks import load_networks
from fastrl.spec import load_spec


def sample(env, suggester, expert, epsilon: float, seed: int, every: int) -> list:
    """Suggestions every `every` steps along one episode of the (degraded) expert."""
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    expert.reset()
    out, done = [], False
    while not done:
        if env.steps % every == 0:
            s = suggester.suggest(env)
            out.append((s.reached, s.ms))
        a = expert.act() if rng.random() >= epsilon else int(rng.integers(env.action_space.n))
        _, _, term, trunc, _ = env.step(a)
        done = term or trunc
    return out


def main() -> None:
    """Measure and print."""
    ap = argparse.ArgumentParser()
    ap.add_argument("run", type=Path)
    ap.add_argument("--episodes", type=int, default=5)
    ap.add_argument("--every", type=int, default=10)
    ap.add_argument("--horizon", type=float, default=3.0)
    ap.add_argument("--epsilon", type=float, nargs="+", default=[0.3, 0.7])
    ap.add_argument("--baselines", action="store_true", help="also measure a no-op and a random policy")
    ap.add_argument("--out", type=Path, default=Path("docs/assist_reach.json"))
    args = ap.parse_args()
    spec = load_spec(args.run / "spec.yaml")
    nets = load_networks(args.run / "networks")
    env = FastEnv(spec)
    suggester = Suggester(spec, nets.policy, args.horizon)
    expert = ScriptedExpert(env)
    result = {
        "run": str(args.run),
        "horizon_s": args.horizon,
        "every_steps": args.every,
        "episodes": args.episodes,
        "epsilon": args.epsilon,
    }
    result["load_average_before"] = os.getloadavg()[0]
    print(machine_line())
    for name, eps in [("expert", 0.0)] + [(f"degraded eps={e:g}", e) for e in args.epsilon]:
        rows = [
            r for s in range(30000, 30000 + args.episodes) for r in sample(env, suggester, expert, eps, s, args.every)
        ]
        reached, ms = np.array([r[0] for r in rows]), np.array([r[1] for r in rows])
        result[name] = {
            "epsilon": eps,
            "states": len(rows),
            "reached_share": float(reached.mean()),
            "ms_median": float(np.median(ms)),
            "ms_p95": float(np.percentile(ms, 95)),
            "ms_max": float(ms.max()),
        }
        print(
            f"{name}: {reached.mean():.1%} of {len(rows)} states reach the next avatar; "
            f"suggestion {np.median(ms):.1f} ms median, {np.percentile(ms, 95):.1f} ms p95, {ms.max():.1f} ms max"
        )
    if args.baselines:  # the same measurement with policies that know nothing: what "reaching" costs by chance
        rng = np.random.default_rng(0)
        for name, pol in (("noop", lambda o: np.zeros(len(o), int)), ("random", lambda o: rng.integers(0, 11, len(o)))):
            base = Suggester(spec, pol, args.horizon)
            rows = [
                r
                for eps in [0.0, *args.epsilon]
                for s in range(30000, 30000 + args.episodes)
                for r in sample(env, base, expert, eps, s, args.every)
            ]
            share = float(np.mean([r[0] for r in rows]))
            result[f"baseline {name} policy"] = {"states": len(rows), "reached_share": share}
            print(f"baseline {name} policy: {share:.1%} of {len(rows)} states (all kinds)")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
