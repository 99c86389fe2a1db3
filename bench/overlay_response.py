"""How a run's learned reward and value answer one deficit: expert recordings on several task instances, each with
a kinematic overlay at rising severity, scored with the run's networks.

    python bench/overlay_response.py RUN_DIR --overlay paused
    python bench/overlay_response.py runs/bench-validity-c/tracelines/paused/runs/tracelines/*-assess-* --seeds 100 101

RUN_DIR is an assess run (its `learned/` holds spec and networks) or a learned run. For each --seeds episode the
scripted expert's recording is replayed as it is and with the overlay at each --severity (fastrl.data.overlays), and
the learned reward and value scores (as `fastrl score` gives them) and time are printed. Within an instance a score
that answers the deficit falls with severity; its spread across instances at severity 0 is what a cohort's ranking
must overcome (RESULTS: validity, the reward without the dome's coordinates).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
from pathlib import Path

import numpy as np
from common import machine_line


def main() -> None:
    from fastrl.assess.scoring import Scorer
    from fastrl.data.cohort import with_overlays
    from fastrl.data.overlays import OVERLAYS
    from fastrl.data.replay import expert_trajectories
    from fastrl.irl.networks import load_networks
    from fastrl.spec import load_spec

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run", type=Path)
    parser.add_argument("--overlay", default="paused", choices=list(OVERLAYS))
    parser.add_argument("--seeds", nargs="+", type=int, default=list(range(100, 106)))
    parser.add_argument("--severity", nargs="+", type=float, default=[0.25, 0.5, 1.0])
    args = parser.parse_args()
    learned = args.run / "learned" if (args.run / "learned").is_dir() else args.run
    spec = load_spec(learned / "spec.yaml")
    scorer = Scorer(spec, load_networks(learned / "networks"))
    print(f"# {machine_line()}\n# {learned}: overlay {args.overlay}")
    base = []
    for k, recording in zip(args.seeds, expert_trajectories(scorer.env, args.seeds)):
        cells = []
        for g in [0.0, *args.severity]:
            traj = with_overlays(scorer.env, recording, {args.overlay: g}, k) if g else recording
            s = scorer.score(traj).scores
            cells.append(f"g={g:g}: reward {s['reward']:7.1f} value {s['value']:5.2f} time {s['time']:4.1f}")
            if not g:
                base.append(s["reward"])
        print(f"seed {k}: " + " | ".join(cells))
    print(
        f"summed reward at g=0 over {len(base)} instances: {min(base):.1f} to {max(base):.1f} (sd {np.std(base):.1f})"
    )


if __name__ == "__main__":
    main()
