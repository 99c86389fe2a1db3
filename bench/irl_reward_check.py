"""Is the learned reward a reward? Spearman correlation of learned and heuristic returns over held-out rollouts.

    python bench/irl_reward_check.py runs/bench-irl/tracelines/*-airl-ppo-s0 [more run dirs] [--episodes 8]
    python bench/irl_reward_check.py --from-json docs/irl_reward_check.json [more results or runs]
    python bench/irl_reward_check.py REWARD_RUN... --pool runs/bench-irl/tracelines/* [...]   # a common pool

For each run (GAIL or AIRL, with networks/ and checkpoints/): the untrained policy (same seed) and every saved
checkpoint are rolled out deterministically on held-out seeds (20000, 20001, ...). Each rollout is scored by the
spec's heuristic reward (w . phi) and by the learned reward saved in networks/ (safetensors), loaded without pickle:
AIRL r_psi(s) (averaged over the copies saved during training, if the run saved them; --final: the final r_psi
alone), GAIL log D - log(1 - D). Prints Spearman's rho over rollouts between the two returns read three ways:
both discounted with the generator's gamma (the learned one with the absorbing tail if the episode ended in
success), both summed undiscounted over the episode, and the learned return discounted against the heuristic
one summed (also, for reference, the learned sum continued to the time limit at the absorbing state's reward,
and rho over per-policy mean returns), each with a 95% interval from resampling the policies (1000 times, each
policy with all its rollouts), and the same readings for a reward of -1 per step, which knows only how long an
episode ran; then, where a task and algorithm have runs of several training seeds, each reading per seed; then,
by the third reading, rho against the heuristic return less each of its weighted terms in turn, which shows the
term the learned reward prices differently, and rho as the terms the run's demonstrations never exercise (zero
at every step, such as contact: the expert shows no price for them) are priced at 0 to 1 times their weight;
writes the results as JSON and figures (learned against heuristic return for the lowest seed of each task and
algorithm; rho against the price of the never-exercised terms).

With --pool, each reward is scored instead on the checkpoints of the pool's runs of its task (PPO on the
heuristic, BC, GAIL, AIRL, any seed) but its own, plus one untrained policy per training seed: policies its
discriminator never saw, the same set for every reward, so rewards of different settings compare directly.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
import re
import warnings
from pathlib import Path

import numpy as np
from common import machine_line
from scipy.stats import spearmanr

READINGS = {  # rho's name: (heuristic, learned) fields of a row
    "spearman_discounted": ("heuristic_discounted", "learned"),  # both discounted with the generator's gamma
    "spearman_sum": ("heuristic", "learned_sum"),  # both summed undiscounted over the episode
    "spearman": ("heuristic", "learned"),  # the learned return discounted, the heuristic one summed
    "spearman_horizon": ("heuristic", "learned_horizon"),  # the learned sum continued to the time limit
}
SILENT_SCALES = (0.0, 0.05, 0.1, 0.25, 0.5, 1.0)  # weights of the terms the demonstrations never exercise, x spec's


def rollout(env, policy, seed: int) -> tuple[np.ndarray, np.ndarray, bool, dict[str, float]]:
    """Observations, heuristic rewards, success and each weighted term's share of the return, of one episode."""
    obs, _ = env.reset(seed=seed)
    observations, rewards, done, info = [obs], [], False, {}
    weights = dict(zip(env.feature_names, env.weights))
    terms = dict.fromkeys(weights, 0.0)
    while not done:
        obs, reward, term, trunc, info = env.step(policy(obs))
        observations.append(obs)
        rewards.append(reward)
        for name, value in info["features"].items():
            terms[name] += weights[name] * value
        done = term or trunc
    return np.array(observations), np.array(rewards), bool(info.get("success", False)), terms


def untrained_policy(spec):
    """The policy a run of this spec starts from (its training seed), as obs -> action."""
    from fastrl.agents.sb3 import build_model, make_vec_env, policy_function

    venv = make_vec_env(spec, 1, spec.train.seed)
    venv.training = False
    with warnings.catch_warnings():  # one env cannot fill a training batch: we only act
        warnings.simplefilter("ignore", UserWarning)
        return policy_function(build_model(spec, venv), venv)


def run_policies(run: Path, untrained: bool = True) -> dict[int, object]:
    """A run's saved policies by training steps: every checkpoint, and the untrained policy (same seed) as 0."""
    from fastrl.runner.runs.saved import checkpoint_policy
    from fastrl.spec import load_spec

    spec = load_spec(run / "spec.yaml")
    policies = {0: untrained_policy(spec)} if untrained else {}
    for ckpt in sorted((run / "checkpoints").glob("[0-9]*")):
        policies[int(ckpt.name)] = checkpoint_policy(spec, ckpt)
    return policies


def rollouts(env, policies: dict[int, object], episodes: int) -> list[dict]:
    """Held-out rollouts (seeds 20000, ...) of each policy: observations, heuristic return, success, length."""
    rows = []
    for steps, policy in policies.items():
        for seed in range(20000, 20000 + episodes):
            obs, rewards, success, terms = rollout(env, policy, seed)
            rows.append(
                {
                    "policy_steps": steps,
                    "seed": seed,
                    "heuristic": float(sum(rewards.tolist())),
                    "terms": terms,
                    "success": success,
                    "steps": len(obs) - 1,
                    "obs": obs,
                    "rewards": rewards,
                }
            )
    return rows


def scored(rows: list[dict], nets, max_steps: int) -> list[dict]:
    """The rows with their learned returns (discounted with tail, undiscounted, undiscounted to the limit) and
    the heuristic return discounted with the same gamma."""
    out = []
    for r in rows:
        obs, success = r["obs"], r["success"]
        learned_sum = float(nets.reward(obs).sum())
        tail = (max_steps - (len(obs) - 1)) * nets.absorbing_reward() if success else 0.0
        discount = nets.gamma ** np.arange(len(r["rewards"]))
        out.append(
            {k: v for k, v in r.items() if k not in ("obs", "rewards")}
            | {
                "learned": nets.learned_return(obs, success),
                "learned_sum": learned_sum,
                "learned_horizon": learned_sum + tail,
                "heuristic_discounted": float(np.sum(discount * r["rewards"])),
            }
        )
    return out


def correlations(rows: list[dict], silent: list[str], key=lambda r: r["policy_steps"]) -> dict:
    """Spearman's rho of heuristic against each learned return over rollouts, and over per-policy means."""
    rho = {
        name: float(spearmanr([r[heuristic] for r in rows], [r[learned] for r in rows]).statistic)
        for name, (heuristic, learned) in READINGS.items()
    }
    policies = list(dict.fromkeys(key(r) for r in rows))
    mean_of = lambda f: [np.mean([r[f] for r in rows if key(r) == p]) for p in policies]  # noqa: E731
    rho["spearman_policy_means"] = float(spearmanr(mean_of("heuristic"), mean_of("learned")).statistic)
    intervals = {
        f"{name}_ci": policy_bootstrap(rows, key, *fields)
        for name, fields in READINGS.items()
        if name != "spearman_horizon"
    }
    steps = [-r["steps"] for r in rows]  # a reward of -1 per step ranks rollouts by length, discounted or not
    length = {
        name: float(spearmanr([r[heuristic] for r in rows], steps).statistic)
        for name, (heuristic, _) in READINGS.items()
        if name != "spearman_horizon"
    }
    return {
        "policies": len(policies),
        "rollouts": len(rows),
        **rho,
        **intervals,
        "length_baseline": length,
        "spearman_without": without_terms(rows),
        "silent_terms": silent,
        "spearman_silent_scaled": silent_scaled(rows, silent),
    }


def policy_bootstrap(
    rows: list[dict], key, heuristic: str = "heuristic", learned: str = "learned", resamples: int = 1000, seed: int = 0
) -> list[float]:
    """95% interval of rho when the policies are resampled with replacement (each with all its rollouts)."""
    groups: dict[object, list[int]] = {}
    for i, r in enumerate(rows):
        groups.setdefault(key(r), []).append(i)
    members = list(groups.values())
    h, g = np.array([r[heuristic] for r in rows]), np.array([r[learned] for r in rows])
    rng = np.random.default_rng(seed)
    rhos = []
    for _ in range(resamples):
        idx = np.concatenate([members[k] for k in rng.integers(0, len(members), len(members))])
        rhos.append(spearmanr(h[idx], g[idx]).statistic)
    return [float(v) for v in np.nanpercentile(rhos, [2.5, 97.5])]


def without_terms(rows: list[dict]) -> dict[str, float]:
    """rho of the learned return against the heuristic return less one weighted term, for each term that varies."""
    learned = [r["learned"] for r in rows]
    return {
        name: float(spearmanr([r["heuristic"] - r["terms"][name] for r in rows], learned).statistic)
        for name in rows[0]["terms"]
        if np.ptp([r["terms"][name] for r in rows]) > 0
    }


def silent_terms(env, run: Path) -> list[str]:
    """Weighted terms that are zero at every step of the run's demonstrations: the expert never shows their price."""
    from fastrl.data.replay import replay
    from fastrl.data.trajectory import load_trajectories

    demos, errors = load_trajectories([run / "demos"]) if (run / "demos").is_dir() else ([], [])
    for err in errors:  # a damaged file is reported; the others still count
        print(f"skipping a demonstration of {run}: {err}")
    if not demos:
        return []
    used = {name for traj in demos for info in replay(env, traj)[1] for name, v in info["features"].items() if v}
    return [name for name, w in zip(env.feature_names, env.weights) if w and name not in used]


def silent_scaled(rows: list[dict], silent: list[str]) -> dict[str, float]:
    """rho of the learned return against the heuristic return with the silent terms' weights scaled by each of
    SILENT_SCALES (1: the spec's heuristic; the demonstrations' returns are the same at every scale)."""
    if not silent:
        return {}
    learned = [r["learned"] for r in rows]
    return {
        f"{k:g}": float(
            spearmanr(
                [r["heuristic"] - (1.0 - k) * sum(r["terms"][n] for n in silent) for r in rows], learned
            ).statistic
        )
        for k in SILENT_SCALES
    }


def setting(spec) -> str:
    """What a run was trained with but its seed, as a hash: runs of one setting differ only in the seed."""
    from fastrl.spec import spec_hash

    return spec_hash(spec.model_copy(update={"train": spec.train.model_copy(update={"seed": 0})}))


def check(run: Path, episodes: int, averaged: bool = True) -> dict:
    """Rollouts of every saved policy of a run, both returns, and their rank correlation."""
    from fastrl.env import FastEnv
    from fastrl.irl.export import load_networks
    from fastrl.spec import load_spec

    spec = load_spec(run / "spec.yaml")
    nets = load_networks(run / "networks", averaged)
    env = FastEnv(spec)
    rows = scored(rollouts(env, run_policies(run), episodes), nets, env.max_steps)
    return {
        "run": str(run),
        "task": spec.name,
        "algorithm": nets.kind,
        "setting": setting(spec),
        "reward_members": nets.reward_members,
        **correlations(rows, silent_terms(env, run)),
        "rows": rows,
    }


def checked(run: Path, episodes: int, averaged: bool) -> dict | None:
    """check(run), or None after saying why when the run has no readable spec or learned reward."""
    from fastrl.spec import SpecError

    try:
        return check(run, episodes, averaged)
    except (SpecError, OSError, ValueError, KeyError) as err:  # report it, check the rest
        print(f"skipping {run}: {err}")
        return None


def check_pool(reward_runs: list[Path], pool: list[Path], episodes: int, averaged: bool = True) -> list[dict]:
    """Each run's learned reward on the policies of the pool's runs of its task but its own (none trained on it)."""
    from rich.progress import track

    from fastrl.env import FastEnv
    from fastrl.irl.export import load_networks
    from fastrl.spec import SpecError, load_spec

    nets = {}
    for run in reward_runs:
        try:
            nets[run] = load_networks(run / "networks", averaged)
        except (OSError, ValueError, KeyError) as err:  # an unfinished or damaged run: report it, check the rest
            print(f"skipping {run}: no learned reward to check ({err})")
    reward_runs = [run for run in reward_runs if run in nets]
    specs = {}
    for run in dict.fromkeys([*reward_runs, *pool]):
        try:
            specs[run] = load_spec(run / "spec.yaml")
        except SpecError as err:  # not a run directory, or its spec is damaged: report it, use the rest
            print(f"skipping {run}: {err}")
    reward_runs, pool = [r for r in reward_runs if r in specs], [r for r in pool if r in specs]
    results = []
    for task in dict.fromkeys(specs[run].name for run in reward_runs):
        members = [run for run in pool if specs[run].name == task]
        if not members:
            raise SystemExit(f"the pool has no run of {task}")
        first = members[0]
        for run in [*members, *(r for r in reward_runs if specs[r].name == task)]:
            if (specs[run].observation, specs[run].reward) != (specs[first].observation, specs[first].reward):
                raise SystemExit(f"{run}: observation or reward differs from {first}'s: returns not comparable")
        env = FastEnv(specs[first])
        by_seed = {specs[run].train.seed: run for run in reversed(members)}  # one untrained policy per seed
        rows: dict[str, list[dict]] = {}
        for seed, run in sorted(by_seed.items()):
            name = f"untrained-s{seed}"
            rows[name] = [r | {"policy_run": name} for r in rollouts(env, {0: untrained_policy(specs[run])}, episodes)]
        for run in track(members, description=f"{task}: rolling out the pool"):
            rows[str(run)] = [
                r | {"policy_run": str(run)} for r in rollouts(env, run_policies(run, untrained=False), episodes)
            ]
        for run in (r for r in reward_runs if specs[r].name == task):
            held_out = [r for name, group in rows.items() if name != str(run) for r in group]
            rows_scored = scored(held_out, nets[run], env.max_steps)
            results.append(
                {
                    "run": str(run),
                    "task": task,
                    "algorithm": nets[run].kind,
                    "setting": setting(specs[run]),
                    "pool": True,
                    "reward_members": nets[run].reward_members,
                    **correlations(
                        rows_scored, silent_terms(env, run), key=lambda r: (r["policy_run"], r["policy_steps"])
                    ),
                    "rows": rows_scored,
                }
            )
    return results


def training_seed(result: dict) -> int | None:
    """The training seed from the run directory's name (...-s<seed>)."""
    m = re.search(r"-s(\d+)$", result["run"].rstrip("/"))
    return int(m.group(1)) if m else None


def label(result: dict) -> str:
    """The algorithm, whether its reward is AIRL's average over training, and whether it was scored on the pool."""
    averaged = " (average)" if result.get("reward_members", 1) > 1 else ""
    return result["algorithm"].upper() + averaged + (" on the pool" if result.get("pool") else "")


def reading(r: dict, name: str, interval: bool = True) -> str:
    """One reading's rho, with its 95% interval if asked and recorded ('-' where older results lack it)."""
    if name not in r:
        return "-"
    ci = r.get(f"{name}_ci")
    return f"{r[name]:.3f}" + (" ({:.2f} to {:.2f})".format(*ci) if interval and ci else "")


def print_tables(results: list[dict]) -> None:
    """One row per run; then, where a task and algorithm have several runs (seeds), each reading per seed."""
    print(
        "| task | algorithm | runs of | seed | policies x episodes | rho: both returns discounted with the "
        "generator's gamma (95% interval, policies resampled) | rho: both summed | rho: learned discounted, "
        "heuristic summed | rho: learned summed to the time limit | rho of per-policy means | rho of -1 per step, "
        "by the same three readings |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        folder = Path(r["run"]).parent.parent.name
        length = r.get("length_baseline", {})
        baseline = (
            ", ".join(f"{length[k]:.2f}" for k in ("spearman_discounted", "spearman_sum", "spearman") if k in length)
            or "-"
        )
        print(
            f"| {r['task']} | {label(r)} | {folder} | {training_seed(r)} | {r['policies']} x "
            f"{r['rollouts'] // r['policies']} | {reading(r, 'spearman_discounted')} | {reading(r, 'spearman_sum')} "
            f"| {reading(r, 'spearman')} | {reading(r, 'spearman_horizon')} | {r['spearman_policy_means']:.3f} | "
            f"{baseline} |"
        )
    groups: dict[tuple, list[dict]] = {}
    for r in results:
        groups.setdefault((r["task"], label(r), r.get("setting")), []).append(r)
    if all(len(g) == 1 for g in groups.values()):
        return
    print(
        "\n| task | algorithm | runs of (first run's folder) | seeds | both discounted, per seed | at >= 0.8 | "
        "both summed, per seed | at >= 0.8 | learned discounted, heuristic summed, per seed | at >= 0.8 |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for (task, algo, _), g in groups.items():
        cells = []
        for name in ("spearman_discounted", "spearman_sum", "spearman"):
            values = [r.get(name) for r in g]
            passed = f"{sum(v >= 0.8 for v in values)} of {len(g)}" if None not in values else "-"
            cells += [", ".join(f"{v:.2f}" if v is not None else "-" for v in values), passed]
        folder = Path(g[0]["run"]).parent.parent.name
        print(f"| {task} | {algo} | {folder} | {len(g)} | " + " | ".join(cells) + " |")


def print_without_terms(results: list[dict]) -> None:
    """Per run: rho against the heuristic return less each term in turn (which term the learned reward prices
    differently)."""
    results = [r for r in results if r.get("spearman_without")]
    for task in dict.fromkeys(r["task"] for r in results):
        rows = [r for r in results if r["task"] == task]
        terms = list(dict.fromkeys(t for r in rows for t in r["spearman_without"]))
        print(f"\n{task}: rho (learned discounted, heuristic summed) against the heuristic return less one term\n")
        print("| algorithm | run | seed | rho | " + " | ".join(f"less {t}" for t in terms) + " |")
        print("|---|---|---|---|" + "---|" * len(terms))
        for r in rows:
            cells = " | ".join(f"{r['spearman_without'][t]:.3f}" if t in r["spearman_without"] else "-" for t in terms)
            print(
                f"| {label(r)} | {Path(r['run']).parent.parent.name} | {training_seed(r)} | {r['spearman']:.3f} | "
                f"{cells} |"
            )


def print_silent_scaled(results: list[dict]) -> None:
    """Per run: rho as the terms its demonstrations never exercise are priced at fractions of the spec's weight."""
    results = [r for r in results if r.get("spearman_silent_scaled")]
    for task in dict.fromkeys(r["task"] for r in results):
        rows = [r for r in results if r["task"] == task]
        scales = list(rows[0]["spearman_silent_scaled"])
        print(
            f"\n{task}: rho (learned discounted, heuristic summed) with the terms the demonstrations never "
            "exercise priced at k x the spec's weight (the demonstrations' returns are the same for every k)\n"
        )
        print("| algorithm | run | seed | terms | " + " | ".join(f"k = {k}" for k in scales) + " |")
        print("|---|---|---|---|" + "---|" * len(scales))
        for r in rows:
            cells = " | ".join(f"{r['spearman_silent_scaled'][k]:.3f}" for k in scales)
            print(
                f"| {label(r)} | {Path(r['run']).parent.parent.name} | {training_seed(r)} | "
                f"{', '.join(r['silent_terms'])} | {cells} |"
            )


def scatter_figure(shown: list[dict], out: Path) -> None:
    """Learned against heuristic return (both discounted, where recorded), one panel per run shown, coloured by the
    policy's training steps."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = min(len(shown), 3)
    rows = -(-len(shown) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.8 * rows), squeeze=False)
    for ax in axes.flat[len(shown) :]:
        ax.set_visible(False)
    for ax, r in zip(axes.flat, shown):
        steps = np.array([x["policy_steps"] for x in r["rows"]]) / 1000
        discounted = "spearman_discounted" in r
        heuristic = "heuristic_discounted" if discounted else "heuristic"
        sc = ax.scatter(
            [x[heuristic] for x in r["rows"]], [x["learned"] for x in r["rows"]], c=steps, s=14, cmap="viridis"
        )
        rho = (
            f"rho {r['spearman_discounted']:.3f} (heuristic summed: {r['spearman']:.3f})"
            if discounted
            else f"rho {r['spearman']:.3f}"
        )
        ax.set_title(
            f"{r['task']} {label(r)}\n{Path(r['run']).parent.parent.name}, seed {training_seed(r)}: {rho}", fontsize=9
        )
        ax.set(xlabel="heuristic return" + (", discounted" if discounted else ""), ylabel="learned return, discounted")
        fig.colorbar(sc, ax=ax, label="policy training steps (thousands)")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)


def silent_figure(results: list[dict], out: Path) -> None:
    """rho against the price of the terms the demonstrations never exercise: a panel per task, a line per run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    results = [r for r in results if r.get("spearman_silent_scaled")]
    tasks = list(dict.fromkeys(r["task"] for r in results))
    labels = list(dict.fromkeys(label(r) for r in results))
    colours = dict(zip(labels, plt.rcParams["axes.prop_cycle"].by_key()["color"] * 3))
    fig, axes = plt.subplots(1, len(tasks), figsize=(5.2 * len(tasks), 4.2), squeeze=False)
    for ax, task in zip(axes[0], tasks):
        shown = set()
        for r in (r for r in results if r["task"] == task):
            name = label(r)
            scan = r["spearman_silent_scaled"]
            ax.plot(
                [float(k) for k in scan],
                list(scan.values()),
                "o-",
                ms=3,
                color=colours[name],
                label=None if name in shown else name,
            )
            shown.add(name)
        ax.axhline(0.8, color="grey", ls="--", lw=1)
        silent = next(r["silent_terms"] for r in results if r["task"] == task)
        ax.set(
            title=f"{task}: never shown {', '.join(silent)}",
            xlabel="their price, times the spec's weight",
            ylabel="Spearman rho",
        )
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main() -> None:
    """Check every run given (or read earlier results), print the tables, write JSON and a figure."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*", type=Path)
    ap.add_argument("--episodes", type=int, default=8, help="held-out seeds per policy")
    ap.add_argument("--figure", default="docs/irl_reward_check.png")
    ap.add_argument(
        "--from-json",
        nargs="*",
        type=Path,
        default=[],
        metavar="JSON",
        help="also take the results an earlier call wrote beside its figure (no rollouts)",
    )
    ap.add_argument(
        "--pool",
        nargs="*",
        type=Path,
        metavar="RUN",
        help="score each run's reward on the checkpoints of these runs of its task (PPO, BC, GAIL, AIRL; "
        "without RUN: the runs above), leaving out its own: policies not trained against it",
    )
    ap.add_argument(
        "--final",
        action="store_true",
        help="score AIRL's final r_psi alone, not its average over the copies saved during training",
    )
    ap.add_argument(
        "--no-rows",
        action="store_true",
        help="write each run's figures but not its per-rollout rows into the JSON (the figure keeps them)",
    )
    args = ap.parse_args()
    if not args.runs and not args.from_json:
        ap.error("give run directories, or --from-json with earlier results")
    print(f"# machine: {machine_line()}")
    results = [r for f in args.from_json for r in json.loads(f.read_text())]
    if args.pool is not None:
        results += check_pool(args.runs, args.pool or args.runs, args.episodes, not args.final)
    else:
        results += [r for run in args.runs if (r := checked(run, args.episodes, not args.final))]
    if not results:
        raise SystemExit("no run could be checked")
    results.sort(key=lambda r: (r["task"], label(r), r.get("setting", ""), training_seed(r) or 0))
    print_tables(results)
    print_without_terms(results)
    print_silent_scaled(results)
    shown = list({(r["task"], label(r), r.get("setting")): r for r in reversed(results) if "rows" in r}.values())[
        ::-1
    ]  # the lowest seed of each setting
    if shown:
        scatter_figure(shown, Path(args.figure))
    silent_out = Path(args.figure).with_name(Path(args.figure).stem + "_silent_terms.png")
    if any(r.get("spearman_silent_scaled") for r in results):
        silent_figure(results, silent_out)
        print(f"figure: {silent_out}")
    if args.no_rows:
        results = [{k: v for k, v in r.items() if k != "rows"} for r in results]
    out = Path(args.figure)
    out.with_suffix(".json").write_text(json.dumps(results, indent=2))
    print(f"figure: {out}" if shown else f"results: {out.with_suffix('.json')}")


if __name__ == "__main__":
    main()
