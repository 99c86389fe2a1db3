"""The colour cue: the learned value of the current state (or the heuristic potential) as a colour."""

from __future__ import annotations

import numpy as np

from ..data.loop import episode_steps
from ..env.fast_env import FastEnv

RED, YELLOW, GREEN = np.array([220, 40, 30]), np.array([240, 200, 30]), np.array([40, 200, 60])


def cue_colour(x: float) -> tuple[int, int, int]:
    """Red (0) through yellow (0.5) to green (1) as RGB uint8 values; x is clipped to [0, 1]."""
    x = float(np.clip(x, 0.0, 1.0))
    c = RED + (YELLOW - RED) * (2 * x) if x < 0.5 else YELLOW + (GREEN - YELLOW) * (2 * x - 1)
    return tuple(int(round(v)) for v in c)


class ValueCue:
    """Learned value V(s) where a run's networks exist, else the heuristic cue potential; scaled to [0, 1]."""

    def __init__(self, networks=None, lo: float = 0.0, hi: float = 1.0):
        self.networks, self.lo, self.hi = networks, lo, hi
        self.kind = "value" if networks is not None else "heuristic"

    def raw(self, env: FastEnv) -> float:
        """The unscaled cue of the env's current state."""
        if self.networks is not None:
            return float(self.networks.value(env.observation()[None])[0])
        return float(env.state.potential)

    def raw_batch(self, obs: np.ndarray, potentials: np.ndarray) -> np.ndarray:
        """Unscaled cues of replayed states: values of observations, or the potentials given."""
        if self.networks is not None:
            return self.networks.value(obs).astype(float)
        return np.asarray(potentials, float)

    def level(self, raw: float) -> float:
        """The cue scaled by the calibration range, clipped to [0, 1]."""
        return float(np.clip((raw - self.lo) / max(self.hi - self.lo, 1e-9), 0.0, 1.0))

    def calibrate(self, env: FastEnv, policies: dict, seed: int = 0) -> dict:
        """Set lo/hi to the 5th/95th percentiles of the cue over one episode of each policy (obs -> action)."""
        seen = []
        for act in policies.values():
            steps = episode_steps(env, seed, policy=lambda _obs, act=act: act(env.observation()))
            seen += [self.raw(env) for _ in steps][:-1]  # the states an action was taken in
        self.lo, self.hi = (float(v) for v in np.percentile(seen, [5, 95]))
        return {"kind": self.kind, "lo": self.lo, "hi": self.hi, "policies": list(policies), "seed": seed}
