"""Do the learned scores hold on cohorts built as an outsider would? Deficits fastrl's trainee model does not make.

    python bench/outside_cohorts.py --tasks tracelines --seeds 0
    python bench/outside_cohorts.py --kinds mix --seeds 0 1 2
    python bench/outside_cohorts.py --from-json docs/outside_cohorts.json     # re-print earlier results

Issue 43 found the learned scores losing to the stopwatch on two cohorts built outside the project from the scripted
expert's recordings. This builds cohorts the same way, with none of fastrl's deficit code (fastrl.data.families and
overlays are not used): the scripted expert's recordings (seeds 0-49, no actions), each deformed by a kind of deficit
written here, level 5 as recorded and level L at severity (5 - L) / 4; `mix`: each subject one to three kinds in
shares of its own. The kinds: a sluggish hand (the poses low-pass filtered, so every move lags), ringing (an
underdamped hand that overshoots and oscillates after each move), pumping (the scope's depth oscillating in and out),
wobble (slow roll and view oscillation), fatigue (the motion slowing toward the end) and spikes (sudden jerks that
decay). Then the paper's protocol as bench/validity.py (`fastrl assess COHORT --top 10`, the shipped spec): Kendall
tau-b against the levels of the learned reward and value beside the heuristic, the stopwatch, the path length and
the subtasks. Nothing in fastrl was chosen on these cohorts: read them as held out (RESULTS.md says which change
first met them). Writes --json (docs/outside_cohorts.json).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse
import json
from pathlib import Path

import numpy as np
from validity import measure_all, table

ROOT = Path("runs/bench-outside")
LEVELS, PER_LEVEL = 5, 10
SCOPE_ONLY = ("tracelines", "imagecentring", "periscoping")  # the kinds deform the scope's poses alone
DEG = np.pi / 180


def sluggish(p: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """Every move lags: first-order low-pass with a time constant of 0.5 g s, run on until it settles."""
    tau = 0.5 * g
    target = np.concatenate([p, np.repeat(p[-1:], int(4 * tau * hz), axis=0)])
    a = (1 / hz) / (tau + 1 / hz)
    y = np.empty_like(target)
    y[0] = target[0]
    for t in range(1, len(target)):
        y[t] = y[t - 1] + a * (target[t] - y[t - 1])
    return y


def ringing(p: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """Overshoot and oscillation after each move: the poses through a 1 Hz hand damped at 0.2, blended in by g."""
    w, zeta, dt = 2 * np.pi * 1.0, 0.2, 1 / hz
    target = np.concatenate([p, np.repeat(p[-1:], int(2 * hz), axis=0)])
    y, v = target[0].copy(), np.zeros(p.shape[1])
    out = np.empty_like(target)
    for t in range(len(target)):
        for _ in range(10):  # semi-implicit Euler on a finer grid
            v += (w * w * (target[t] - y) - 2 * zeta * w * v) * dt / 10
            y = y + v * dt / 10
        out[t] = y
    return target + g * (out - target)


def _phase(n: int, hz: float, band: tuple[float, float], rng: np.random.Generator) -> np.ndarray:
    """A sine of a random frequency in `band` (Hz) and random phase, n samples at `hz`."""
    return np.sin(2 * np.pi * rng.uniform(*band) * np.arange(n) / hz + rng.uniform(0, 2 * np.pi))


def pumping(p: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """The depth oscillates: insertion in and out by up to 6 g mm at 0.3-0.7 Hz."""
    out = p.copy()
    out[:, 2] += g * 0.006 * _phase(len(p), hz, (0.3, 0.7), rng)
    return out


def wobble(p: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """The view wobbles slowly: roll by up to 15 g degrees, pitch and yaw by 1.5 g, at 0.15-0.4 Hz."""
    out = p.copy()
    for j, amplitude in ((0, 1.5), (1, 1.5), (3, 15.0)):
        out[:, j] += g * amplitude * DEG * _phase(len(p), hz, (0.15, 0.4), rng)
    return out


def fatigue(p: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """The motion slows toward the end: playback speed falls from 1 to 1 / (1 + 3 g) along the recording."""
    n, u, steps = len(p), 0.0, [0.0]
    while u < n - 1:
        u += 1.0 / (1.0 + 3.0 * g * u / (n - 1))
        steps.append(min(u, n - 1))
    return np.column_stack([np.interp(steps, np.arange(n), p[:, j]) for j in range(p.shape[1])])


def spikes(p: np.ndarray, g: float, rng: np.random.Generator, hz: float) -> np.ndarray:
    """Sudden jerks: about one per 1.5 / g s, 4 degrees of pitch or yaw that decay in 0.25 s."""
    out, t = p.copy(), np.arange(len(p)) / hz
    for t0 in rng.uniform(0, t[-1], 1 + rng.poisson(g * t[-1] / 1.5)):
        after = t >= t0
        out[after, rng.integers(0, 2)] += rng.choice([-4.0, 4.0]) * DEG * np.exp(-(t[after] - t0) / 0.25)
    return out


KINDS = {
    "sluggish": sluggish,
    "ringing": ringing,
    "pumping": pumping,
    "wobble": wobble,
    "fatigue": fatigue,
    "spikes": spikes,
}


def deformed(portal: np.ndarray, mix: dict[str, float], level: int, seed: int, hz: float, ranges) -> np.ndarray:
    """The recorded poses with each kind of the subject's mix at its share of the level's severity."""
    rng = np.random.default_rng([seed, 4243])
    severity = (LEVELS - level) / (LEVELS - 1)
    for kind, share in mix.items():
        if severity * share > 0:
            portal = KINDS[kind](portal, severity * share, rng, hz)
    return np.clip(portal, ranges[:, 0], ranges[:, 1])


def subject_mix(kind: str, seed: int) -> dict[str, float]:
    """One kind alone, or for `mix` one to three kinds in random shares."""
    if kind != "mix":
        return {kind: 1.0}
    rng = np.random.default_rng([seed, 977])
    chosen = rng.choice(sorted(KINDS), int(rng.integers(1, 4)), replace=False)
    return {str(k): float(w) for k, w in zip(chosen, rng.dirichlet(np.ones(len(chosen))))}


def cohort(task: str, kind: str, root: Path) -> Path:
    """The kind's 5 x 10 cohort of the task from the scripted expert's recordings, written once."""
    from fastrl.agents.expert import ScriptedExpert
    from fastrl.data.replay import rollout_trajectory
    from fastrl.data.trajectory import Trajectory
    from fastrl.env.fast_env import FastEnv
    from fastrl.spec import load_spec, task_hash

    spec = load_spec(f"specs/{task}.yaml")
    out = root / task / kind / "cohort"
    files = sorted(out.glob("*.npz"))
    if len(files) == LEVELS * PER_LEVEL and Trajectory.load(files[0]).meta.get("task_hash") == task_hash(spec):
        return out
    out.mkdir(parents=True, exist_ok=True)
    env = FastEnv(spec)
    expert = ScriptedExpert(env)
    hz = spec.episode.control_hz
    for level in range(1, LEVELS + 1):
        for i in range(PER_LEVEL):
            seed = (level - 1) * PER_LEVEL + i
            name = f"L{level}-S{i + 1:02d}"
            mix = subject_mix(kind, seed)
            meta = {"source": "synthetic", "subject": name, "skill": level, "levels": LEVELS, "deficits": mix}
            recorded = rollout_trajectory(env, expert.act, seed, meta, expert.reset)[0]
            portal = deformed(recorded.portal, mix, level, seed, hz, env.task.ranges)
            Trajectory(np.arange(len(portal)) / hz, portal, recorded.meta).save(out / f"{name}.npz")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tasks", nargs="+", default=["tracelines"], choices=SCOPE_ONLY)
    parser.add_argument("--kinds", nargs="+", default=[*KINDS, "mix"], choices=[*KINDS, "mix"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--root", type=Path, default=ROOT)
    parser.add_argument("--set", dest="sets", action="append", default=[], help="spec change, as fastrl's --set")
    parser.add_argument("--json", type=Path, default=Path("docs/outside_cohorts.json"))
    parser.add_argument("--from-json", type=Path, help="print the table of an earlier run and stop")
    args = parser.parse_args()
    if args.from_json:
        print(table(json.loads(args.from_json.read_text())["rows"]))
        return
    args.families = args.kinds
    measure_all(args, lambda kind: tuple(args.sets), make=cohort)


if __name__ == "__main__":
    main()
