"""Is the learned reward a reward? Spearman correlation of learned and heuristic returns over held-out rollouts.

    python bench/irl_reward_check.py runs/bench-irl/tracelines/*-airl-ppo-s0 [more run dirs] [--episodes 8]
    python bench/irl_reward_check.py --from-json docs/irl_reward_check.json [more results or runs]

For each run (GAIL or AIRL, with networks/ and checkpoints/): the untrained policy (same seed) and every saved
checkpoint are rolled out deterministically on held-out seeds (20000, 20001, ...). Each rollout is scored by the
spec's heuristic return (sum of w . phi) and by the learned reward saved in networks/reward.pt, loaded without
pickle: AIRL r_psi(s), GAIL log D - log(1 - D), discounted with the generator's gamma plus the absorbing tail if
the episode ended in success. Prints Spearman's rho over rollouts (and, for reference, with the undiscounted
sum of learned rewards without the tail; undiscounted to the time limit, a finished episode's remaining steps
at the absorbing state's reward, as the heuristic return is undiscounted; and over per-policy mean returns),
then, where a task and algorithm have runs of several training seeds, rho's mean ± sd over them; writes the
results as JSON and a scatter figure (the lowest seed of each task and algorithm).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import platform
import re
import warnings
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr


def rollout(env, policy, seed: int) -> tuple[np.ndarray, float, bool]:
    """Observations, heuristic return and success of one deterministic episode."""
    obs, _ = env.reset(seed=seed)
    observations, total, done, info = [obs], 0.0, False, {}
    while not done:
        obs, reward, term, trunc, info = env.step(policy(obs))
        observations.append(obs)
        total += reward
        done = term or trunc
    return np.array(observations), total, bool(info.get("success", False))


def check(run: Path, episodes: int) -> dict:
    """Rollouts of every saved policy of a run, both returns, and their rank correlation."""
    from fastrl.agents.sb3 import build_model, make_vec_env, policy_function
    from fastrl.env import FastEnv
    from fastrl.irl.export import load_networks
    from fastrl.runner.saved import checkpoint_policy
    from fastrl.spec import load_spec

    spec = load_spec(run / "spec.yaml")
    nets = load_networks(run / "networks")
    env = FastEnv(spec)
    venv = make_vec_env(spec, 1, spec.train.seed)
    venv.training = False
    with warnings.catch_warnings():  # one env cannot fill a training batch: we only act
        warnings.simplefilter("ignore", UserWarning)
        policies = {0: policy_function(build_model(spec, venv), venv)}
    for ckpt in sorted((run / "checkpoints").glob("[0-9]*")):
        policies[int(ckpt.name)] = checkpoint_policy(spec, ckpt)
    rows = []
    for steps, policy in policies.items():
        for seed in range(20000, 20000 + episodes):
            obs, heuristic, success = rollout(env, policy, seed)
            learned_sum = float(nets.reward(obs).sum())
            tail = (env.max_steps - (len(obs) - 1)) * nets.absorbing_reward() if success else 0.0
            rows.append({"policy_steps": steps, "seed": seed, "heuristic": heuristic, "success": success,
                         "steps": len(obs) - 1, "learned": nets.learned_return(obs, success),
                         "learned_sum": learned_sum, "learned_horizon": learned_sum + tail})
    h = [r["heuristic"] for r in rows]
    rho = spearmanr(h, [r["learned"] for r in rows]).statistic
    rho_sum = spearmanr(h, [r["learned_sum"] for r in rows]).statistic
    rho_horizon = spearmanr(h, [r["learned_horizon"] for r in rows]).statistic
    mean_of = lambda key: [np.mean([r[key] for r in rows if r["policy_steps"] == s]) for s in policies]  # noqa: E731
    rho_policy = spearmanr(mean_of("heuristic"), mean_of("learned")).statistic
    return {"run": str(run), "task": spec.name, "algorithm": nets.kind, "policies": len(policies),
            "rollouts": len(rows), "spearman": float(rho), "spearman_sum": float(rho_sum),
            "spearman_horizon": float(rho_horizon),
            "spearman_policy_means": float(rho_policy), "rows": rows}


def training_seed(result: dict) -> int | None:
    """The training seed from the run directory's name (...-s<seed>)."""
    m = re.search(r"-s(\d+)$", result["run"].rstrip("/"))
    return int(m.group(1)) if m else None


def print_tables(results: list[dict]) -> None:
    """One row per run; then, where a task and algorithm have several runs (seeds), mean ± sd over them."""
    print("| task | algorithm | seed | policies x episodes | Spearman rho (learned return vs heuristic) | "
          "rho, undiscounted sum without tail | rho, undiscounted to the time limit | rho of per-policy means |")
    print("|---|---|---|---|---|---|---|---|")
    for r in results:
        horizon = f"{r['spearman_horizon']:.3f}" if "spearman_horizon" in r else "-"  # not in older results
        print(f"| {r['task']} | {r['algorithm'].upper()} | {training_seed(r)} | {r['policies']} x "
              f"{r['rollouts'] // r['policies']} | {r['spearman']:.3f} | {r['spearman_sum']:.3f} | {horizon} | "
              f"{r['spearman_policy_means']:.3f} |")
    groups: dict[tuple, list[dict]] = {}
    for r in results:
        groups.setdefault((r["task"], r["algorithm"]), []).append(r)
    if all(len(g) == 1 for g in groups.values()):
        return
    print("\n| task | algorithm | seeds | rho, mean ± sd | per seed | runs at >= 0.8 |")
    print("|---|---|---|---|---|---|")
    for (task, algo), g in groups.items():
        rhos = np.array([r["spearman"] for r in g])
        per_seed = ", ".join(f"{r['spearman']:.2f}" for r in g)
        print(f"| {task} | {algo.upper()} | {len(g)} | {rhos.mean():.2f} ± {rhos.std():.2f} | {per_seed} | "
              f"{int((rhos >= 0.8).sum())} of {len(g)} |")


def main() -> None:
    """Check every run given (or read earlier results), print the tables, write JSON and a figure."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*", type=Path)
    ap.add_argument("--episodes", type=int, default=8, help="held-out seeds per policy")
    ap.add_argument("--figure", default="docs/irl_reward_check.png")
    ap.add_argument("--from-json", nargs="*", type=Path, default=[], metavar="JSON",
                    help="also take the results an earlier call wrote beside its figure (no rollouts)")
    args = ap.parse_args()
    if not args.runs and not args.from_json:
        ap.error("give run directories, or --from-json with earlier results")
    print(f"# machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.1f}")
    results = [r for f in args.from_json for r in json.loads(f.read_text())]
    results += [check(run, args.episodes) for run in args.runs]
    results.sort(key=lambda r: (r["task"], r["algorithm"], training_seed(r) or 0))
    print_tables(results)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = list({(r["task"], r["algorithm"]): r for r in reversed(results)}.values())[::-1]  # lowest seed each
    cols = min(len(shown), 3)
    rows = -(-len(shown) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.8 * rows), squeeze=False)
    for ax in axes.flat[len(shown):]:
        ax.set_visible(False)
    for ax, r in zip(axes.flat, shown):
        steps = np.array([x["policy_steps"] for x in r["rows"]])
        sc = ax.scatter([x["heuristic"] for x in r["rows"]], [x["learned"] for x in r["rows"]], c=steps, s=14,
                        cmap="viridis")
        ax.set(title=f"{r['task']} {r['algorithm'].upper()}: rho {r['spearman']:.2f}", xlabel="heuristic return",
               ylabel="learned return")
        fig.colorbar(sc, ax=ax, label="policy training steps")
    fig.tight_layout()
    out = Path(args.figure)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    out.with_suffix(".json").write_text(json.dumps(results, indent=2))
    print(f"figure: {out}")


if __name__ == "__main__":
    main()
