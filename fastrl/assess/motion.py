"""The motion's likelihood: how much like the recordings it learned from a trajectory moves, step by step, for how
long (RESULTS: the motion's likelihood under the recordings')."""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path

import numpy as np

FILE = "motion.safetensors"  # beside the learned networks
SPEED, TURN = "tip_vel", "tip_quat_rate"  # the observation terms a step's motion is read from
RIDGE = 1e-3  # added to the steps' correlation matrix: recordings whose features move together stay a density
ARRAYS = ("reference", "floor", "mean", "spread")  # a model's arrays; files before 2026-12-07 lack its scalars


def motion_columns(spec) -> tuple[list[int], list[int]] | None:
    """The observation columns of the camera's velocity and quaternion rate; None where the spec observes neither,
    stacks frames, or gives the trainee instruments beside the scope (the camera's motion is then not the skill: on
    Triangulation's pauses the likelihood read 0.10, RESULTS)."""
    from ..spec.columns import column_terms

    if spec.instruments or spec.observation.stack != 1:
        return None
    names = column_terms(spec)
    speed, turn = ([i for i, n in enumerate(names) if n == term] for term in (SPEED, TURN))
    return (speed, turn) if speed and turn else None


def transition_motion(obs: np.ndarray, next_obs: np.ndarray, columns: tuple[list[int], list[int]]) -> np.ndarray:
    """Each transition's camera speed and turn rate on arrival, and how much each changed on the way: (n, 4)."""
    before, after = ([np.linalg.norm(o[:, c], axis=1) for c in columns] for o in (obs, next_obs))
    moving = np.column_stack(after)
    return np.column_stack([moving, np.abs(moving - np.column_stack(before))])


def step_motion(obs: np.ndarray, columns: tuple[list[int], list[int]]) -> np.ndarray:
    """Each step's camera speed and turn rate, and how much each changed since the step before (none at the first):
    (n, 4)."""
    return transition_motion(np.concatenate([obs[:1], obs[:-1]]), obs, columns)


@dataclass(frozen=True, kw_only=True)
class MotionModel:
    """A Gaussian kernel density of the recordings' steps, in log and standardised: each kernel shaped as their
    correlation, scaled by Scott's factor (as scipy's gaussian_kde), kept invertible by RIDGE."""

    reference: np.ndarray  # (m, 4) the recordings' steps, standardised
    floor: np.ndarray  # (4,) added before the log: 5% of the recordings' median step, a motion at rest
    mean: np.ndarray  # (4,) of the logged steps
    spread: np.ndarray  # (4,)
    ceiling: float = 0.0  # the highest log-density of any of the recordings' steps
    reward_weight: float = 0.0  # what a step's log-density below the ceiling adds to the learned reward, per nat
    value_weight: float = 0.0  # the same in the units of the learned value (the generator's reward scaling)

    @classmethod
    def fit(cls, steps: list[np.ndarray]) -> MotionModel:
        """The density of every step of these recordings (step_motion's arrays)."""
        ref = np.concatenate(steps).astype(float)
        floor = np.maximum(np.median(ref, 0) * 0.05, 1e-6)
        logged = np.log(ref + floor)
        mean, spread = logged.mean(0), logged.std(0) + 1e-9
        model = cls(reference=(logged - mean) / spread, floor=floor, mean=mean, spread=spread)
        return replace(model, ceiling=float(model.log_density(ref).max()))

    def weighing(self, reward_weight: float, value_weight: float) -> MotionModel:
        """The same density, adding `reward_weight` times each step's log-density below the ceiling to the reward,
        and `value_weight` times its discounted sum from each state on to the value."""
        return replace(self, reward_weight=float(reward_weight), value_weight=float(value_weight))

    @cached_property
    def _kernels(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """(whitening matrix, whitened reference, its squared norms, log normaliser): once per model, not per
        trajectory scored."""
        m, d = self.reference.shape
        factor = m ** (-1.0 / (d + 4))  # Scott's
        lower = np.linalg.cholesky(np.cov(self.reference, rowvar=False) + RIDGE * np.eye(d)) * factor
        whiten = np.linalg.inv(lower)
        ref = self.reference @ whiten.T
        norm = np.log(m) + np.log(np.diag(lower)).sum() + 0.5 * d * np.log(2 * np.pi)
        return whiten, ref, (ref**2).sum(1), float(norm)

    def log_density(self, steps: np.ndarray) -> np.ndarray:
        """Each step's log-density (below zero on average on the FAST tasks), in chunks of 2048 steps."""
        from scipy.special import logsumexp

        whiten, ref, ref_squared, norm = self._kernels
        x = ((np.log(steps + self.floor) - self.mean) / self.spread) @ whiten.T
        chunks = [x[i : i + 2048] for i in range(0, len(x), 2048)]
        squared = ((c**2).sum(1)[:, None] + ref_squared[None, :] - 2.0 * c @ ref.T for c in chunks)
        return np.concatenate([logsumexp(-0.5 * np.maximum(d, 0.0), axis=1) - norm for d in squared] or [[]])

    def log_likelihood(self, steps: np.ndarray) -> float:
        """The summed log-density of a trajectory's steps: a step unlike the recordings' scores lower, and each adds
        its log-density, so the sum reads how a trainee moves and for how long."""
        return float(self.log_density(steps).sum())

    def reward(self, log_density: np.ndarray) -> np.ndarray:
        """The learned reward's motion term of steps of these log-densities: reward_weight times each one's distance
        below the ceiling (never above zero for a recorded step)."""
        return self.reward_weight * (log_density - self.ceiling)

    def value(self, log_density: np.ndarray, gamma: float) -> np.ndarray:
        """The learned value's motion term of each state of a trajectory whose transitions have these log-densities:
        value_weight times the discounted sum of the steps' distances below the ceiling from that state to the end,
        as the trajectory moved on (0 at its last state). The generator's critic prices where a trainee is; how they
        move from there is their own."""
        from scipy.signal import lfilter

        below = self.value_weight * (np.asarray(log_density, dtype=float) - self.ceiling)
        return np.append(lfilter([1.0], [1.0, -gamma], below[::-1])[::-1], 0.0)

    def save(self, path: Path) -> Path:
        """Write the model as safetensors (atomically)."""
        from safetensors.numpy import save

        from ..atomic import atomic_write

        tensors = {k: np.ascontiguousarray(getattr(self, k), dtype=np.float64) for k in self.__dataclass_fields__}
        data = save(tensors, metadata={"format": "fastrl motion model 1"})
        return atomic_write(Path(path), lambda f: f.write(data))

    @classmethod
    def load(cls, path: Path) -> MotionModel:
        """Read a model save() wrote; ValueError names a file that is not one."""
        from safetensors.numpy import load

        try:
            tensors = load(Path(path).read_bytes())
            scalars = {
                k: float(tensors[k].ravel()[0]) for k in cls.__dataclass_fields__ if k in tensors and k not in ARRAYS
            }
            return cls(**{k: tensors[k] for k in ARRAYS}, **scalars)
        except Exception as e:  # a torn or foreign file: safetensors' own errors, a missing tensor
            raise ValueError(f"{path}: not a motion model ({type(e).__name__}: {e})") from None
