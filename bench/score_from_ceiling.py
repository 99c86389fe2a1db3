"""How the learned scores rank a cohort when summed raw, averaged, or counted from the demonstrations' best.

    python bench/score_from_ceiling.py runs/bench-validity-c/tracelines/*/runs/tracelines/*-assess-airl-s*
    python bench/score_from_ceiling.py RUN... --json docs/score_from_ceiling.json

Each RUN is an assess run of `bench/validity.py` (its `learned/` networks, its `best/` recordings; the family's cohort
two folders up). Nothing is trained: the run's networks score its cohort four ways, and each way's Kendall tau-b
against the skill labels is printed beside the stopwatch's and the path length's:
- reward, raw sum: the sum of r_psi(s) (GAIL: the logit) over the replayed steps (fastrl before 2026-11-27);
- reward, from its ceiling: the sum of r - r*, r* the highest reward of any step of the best recordings (shipped);
- value, mean: the mean of V(s) over the replayed states (fastrl before 2026-11-27);
- value, from its ceiling: the sum of V - V*, V* the highest value of any state of the best recordings (shipped).
The ceilings are those `fastrl assess` now saves with the networks (the same recordings, replayed the same way).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
from pathlib import Path

import numpy as np
from common import machine_line, utc_stamp

WAYS = ("reward_sum", "reward_from_ceiling", "value_mean", "value_from_ceiling", "time", "path_length")


def replayed(scorer, folder: Path) -> list[tuple[dict, np.ndarray]]:
    """(scores and metadata, observations) of every trajectory file in a folder, replayed in name order."""
    out = []
    for f in sorted(folder.glob("*.npz")):
        scored, obs = scorer.replayed(scorer.load_file(f), f.stem)
        out.append(({**scored.scores, **scored.meta}, obs))
    return out


def rescored(run: Path) -> dict:
    """The four ways' (and the simple metrics') Kendall tau-b of one assess run's cohort."""
    from scipy.stats import kendalltau

    from fastrl.assess.scoring import Scorer
    from fastrl.irl.export import demonstrated_ceilings
    from fastrl.irl.fitting import Transitions
    from fastrl.irl.networks import load_networks
    from fastrl.spec import load_spec

    learned = run / "learned"
    nets = load_networks(learned / "networks")
    scorer = Scorer(load_spec(learned / "spec.yaml"), nets)
    best = [obs for _, obs in replayed(scorer, run / "best")]
    obs, nxt = np.concatenate([o[:-1] for o in best]), np.concatenate([o[1:] for o in best])
    shown = Transitions(obs, nxt, np.zeros(len(obs)), np.zeros((len(obs), 1)))  # terminals and actions unused
    ceilings = demonstrated_ceilings(nets, shown)  # as `fastrl assess` saves them now
    r_star, v_star = ceilings["reward"], ceilings["value"]
    cols = {k: [] for k in WAYS}
    labels = []
    for scores, obs in replayed(scorer, run.parents[2] / "cohort"):
        r, v = nets.reward(obs).astype(float), nets.value(obs).astype(float)
        cols["reward_sum"].append(r.sum())
        cols["reward_from_ceiling"].append((r - r_star).sum())
        cols["value_mean"].append(v.mean())
        cols["value_from_ceiling"].append((v - v_star).sum())
        cols["time"].append(-scores["time"])
        cols["path_length"].append(-scores["path_length"])
        labels.append(scores["skill"])
    taus = {k: float(kendalltau(v, labels, variant="b").statistic) for k, v in cols.items()}
    return {"run": str(run), "family": run.parents[2].name, "task": run.parents[3].name, "tau_b": taus}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    print(f"# {utc_stamp()}, {machine_line()}")
    print("| task | family | run | " + " | ".join(WAYS) + " |\n|" + "---|" * (len(WAYS) + 3))
    rows = []
    for run in args.runs:
        if not (run / "learned" / "networks" / "reward.safetensors").is_file():
            print(f"skipped {run}: no learned reward in learned/networks")
            continue
        rows.append(rescored(run))
        t = rows[-1]["tau_b"]
        cells = " | ".join(f"{t[k]:.2f}" for k in WAYS)
        print(f"| {rows[-1]['task']} | {rows[-1]['family']} | {run.name} | {cells} |", flush=True)
    if args.json:
        args.json.write_text(json.dumps({"machine": machine_line(), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
