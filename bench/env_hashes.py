"""Same-seed hashes of the bundled specs' env trajectories: run before and after an env change, compare.

    python bench/env_hashes.py --out before.json
    python bench/env_hashes.py --check before.json     # exit 1 on any difference

Per spec: two seeded episodes of a seeded random policy, two of the scripted expert, the expert's episode
replayed through `replay_step`, and an episode continued in a second env after `copy_state_from`; each hashes
observations, rewards, terminated/truncated and infos. Other action modes and the avatar jitter besides.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

import fastrl
from fastrl.agents.expert import ScriptedExpert

SPECS = Path(fastrl.__file__).parent / "specs"
RANDOM_STEPS, EXPERT_STEPS = 120, 400
EXTRA = (  # (spec, label, overrides): other action modes, and the avatar jitter no bundled spec uses
    ("imagecentring", "continuous", ["actions.mode=continuous"]),
    ("tracelines", "rates", ["actions.mode=rates"]),
    ("triangulation", "rates", ["actions.mode=rates"]),
    ("imagecentring", "jitter", ["episode.resets.avatar_jitter={plate: 0.01, dome: 8}"]),
    ("triangulation", "jitter", ["episode.resets.avatar_jitter={plate: 0.01, dome: 8}"]),
)


class Digest:
    """A running sha256 over observations, rewards, flags and infos."""

    def __init__(self):
        self.h = hashlib.sha256()

    def obs(self, o) -> None:
        """Add an observation (array or dict of arrays)."""
        for part in [o[k] for k in sorted(o)] if isinstance(o, dict) else [o]:
            a = np.ascontiguousarray(part)
            self.h.update(str((a.dtype, a.shape)).encode() + a.tobytes())

    def step(self, o, r, term, trunc, info) -> None:
        """Add one step's results."""
        self.obs(o)
        self.h.update(repr((float(r), bool(term), bool(trunc))).encode())
        self.info(info)

    def info(self, info) -> None:
        """Add an info dict, its floats as exact reprs."""
        self.h.update(json.dumps(info, sort_keys=True, default=repr).encode())

    def hex(self) -> str:
        """The digest so far."""
        return self.h.hexdigest()[:16]


def episodes(env, policy: str, seeds, steps: int, record: list | None = None) -> str:
    """Hash seeded episodes of the random policy or the expert; optionally record the expert's coordinates."""
    d = Digest()
    u = env.unwrapped
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        d.obs(obs)
        d.info(info)
        env.action_space.seed(seed)
        expert = ScriptedExpert(env) if policy == "expert" else None
        for _ in range(steps):
            if record is not None:
                record.append((u.portal_coordinates(), u.instrument_coordinates(), u.body_poses()))
            out = env.step(expert.act(obs) if expert else env.action_space.sample())
            obs = out[0]
            d.step(*out)
            if out[2] or out[3]:
                break
        if record is not None:
            record.append((u.portal_coordinates(), u.instrument_coordinates(), u.body_poses()))
            record = None  # the first episode only
    return d.hex()


def replayed(env, record: list) -> str:
    """Hash the replay of recorded coordinates."""
    d = Digest()
    u = env.unwrapped
    q, tq, b = record[0]
    obs, info = env.reset(seed=0, options={"portal": q, **({"instruments": tq} if len(tq) else {})})
    d.obs(obs)
    d.info(info)
    for q, tq, b in record[1:]:
        d.step(*u.replay_step(q, tq if len(tq) else None, b))
    return d.hex()


def continued(make) -> str:
    """Hash an episode continued in a second env from the first one's state (as assist does)."""
    a, b = make(), make()
    d = Digest()
    obs, _ = a.reset(seed=5)
    a.action_space.seed(5)
    for _ in range(30):
        a.step(a.action_space.sample())
    b.reset(seed=99)
    b.copy_state_from(a)
    d.obs(b.observation())
    b.action_space.seed(6)
    for _ in range(60):
        out = b.step(b.action_space.sample())
        d.step(*out)
        if out[2] or out[3]:
            break
    a.close()
    b.close()
    return d.hex()


def late(make) -> str:
    """Hash unseeded resets of an env with late starts (after one seeded reset)."""
    env = fastrl.env.FastEnv(make().task_spec, late_starts=0.5)
    d = Digest()
    env.reset(seed=11)
    for _ in range(3):
        obs, info = env.reset()
        d.obs(obs)
        d.info(info)
    env.close()
    return d.hex()


def hashes() -> dict[str, str]:
    """Every hash, keyed spec/mode/what."""
    out = {}
    runs = [(p.stem, "own", []) for p in sorted(SPECS.glob("*.yaml"))] + list(EXTRA)
    for name, label, overrides in runs:
        path = str(SPECS / f"{name}.yaml")

        def make(path=path, overrides=overrides):
            return fastrl.make(path, overrides=overrides)

        key = f"{name}/{label}"
        env = make()
        out[f"{key}/random"] = episodes(env, "random", (0, 1), RANDOM_STEPS)
        record: list = []
        out[f"{key}/expert"] = episodes(env, "expert", (2, 3), EXPERT_STEPS, record)
        out[f"{key}/replay"] = replayed(make(), record)
        out[f"{key}/continued"] = continued(make)
        if label == "own":
            out[f"{key}/late"] = late(make)
        env.close()
        print(key, {k.rsplit("/", 1)[1]: v for k, v in out.items() if k.startswith(key + "/")}, flush=True)
    return out


def main() -> int:
    """Write or check the hashes."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path)
    ap.add_argument("--check", type=Path)
    args = ap.parse_args()
    live = hashes()
    if args.out:
        args.out.write_text(json.dumps(live, indent=1, sort_keys=True) + "\n")
    if args.check:
        ref = json.loads(args.check.read_text())
        bad = sorted(k for k in set(ref) | set(live) if ref.get(k) != live.get(k))
        print("identical" if not bad else f"DIFFERENT: {bad}")
        return 1 if bad else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
