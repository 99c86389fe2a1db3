"""The scripted expert: inverse portal kinematics toward the current avatar, then servo there."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..env.fast_env import FastEnv
from ..model.kinematics import Kinematics, solve_view

RESOLVE_EVERY = 15  # steps without green at the goal before the view is solved again


class ScriptedExpert:
    """Drives a FastEnv through every subtask; `act()` returns an action in the env's action space."""

    def __new__(cls, env, *args, scope_only: bool = False, **kwargs):
        """A task with instruments gets the two-instrument expert, which drives the scope through a scope-only one."""
        if cls is ScriptedExpert and not scope_only and env.unwrapped.task.instruments:
            from .instruments_expert import TwoInstrumentExpert

            return TwoInstrumentExpert(env, ScriptedExpert(env, *args, scope_only=True, **kwargs))
        return super().__new__(cls)

    def __init__(self, env, pivot_weight: float | None = None, cable_weight: float = 0.005, scope_only: bool = False):
        self.env: FastEnv = env.unwrapped
        self.kin = Kinematics(self.env.task)
        periscoping = self.env.task_spec.task.kind == "periscoping"
        self.pivot_weight = pivot_weight if pivot_weight is not None else (0.3 if periscoping else 0.02)
        self.cable_weight = cable_weight  # cost of turning the light cable when solving the view
        self.mode = self.env.task_spec.actions.mode
        self.discrete = self.mode == "discrete"
        if self.discrete:
            self.steps = np.abs(self.env.actions.table[1::2].sum(axis=1))
        nv = self.env.model.nv
        self.jacp, self.jacr = np.zeros((3, nv)), np.zeros((3, nv))
        self.goal, self.goal_for, self.waiting = None, -1, 0
        self.level = True  # solve for a level horizon too (the two-instrument expert, whose tasks ignore it, does not)

    def reset(self) -> None:
        """Forget the current goal (call after env.reset)."""
        self.goal, self.goal_for, self.waiting = None, -1, 0

    def act(self, obs=None):
        """Next action toward the current avatar's view."""
        env = self.env
        if env.steps == 0:  # a new episode: the old goal belongs to the previous one
            self.reset()
        k = min(env.done_count, len(env.t_pos) - 1)
        return self.to_action(self.error(env.portal_coordinates(), k))

    def error(self, q: np.ndarray, k: int) -> np.ndarray:
        """Goal minus q for subtask k; the view is solved again for a new subtask or after waiting too long."""
        env = self.env
        if self.goal_for != k or self.waiting > RESOLVE_EVERY:
            target = (env.t_pos[k], env.t_fwd[k], env.t_up[k])
            self.goal, _ = solve_view(
                self.kin, k, q, target, self.pivot_weight, cable_weight=self.cable_weight, level=self.level
            )
            self.goal_for, self.waiting = k, 0
        return self.goal - q

    def to_action(self, err: np.ndarray):
        """The action that reduces a portal-coordinate error."""
        if self.discrete:
            return self._discrete(err)
        return self._rates(err) if self.mode == "rates" else self._continuous(err)

    def _discrete(self, err: np.ndarray) -> int:
        """One increment on the coordinate furthest from the goal; retract first, insert last."""
        ratio = err / self.steps
        if ratio[2] < -0.6:
            return 6
        order = np.argsort(-np.abs(ratio[[0, 1, 3, 4]]))
        k = [0, 1, 3, 4][order[0]]
        if abs(ratio[k]) > 0.6:
            return 1 + 2 * k + (0 if err[k] > 0 else 1)
        if ratio[2] > 0.6:
            return 5
        self.waiting += 1
        return 0

    def _rates(self, err: np.ndarray) -> np.ndarray:
        """Portal rates proportional to the remaining error, saturating at the maximum rates."""
        step = self.env.actions.step
        if np.abs(err).max() < 1e-3:
            self.waiting += 1
        return np.clip(0.5 * err / step, -1.0, 1.0).astype(np.float32)

    def _continuous(self, err: np.ndarray) -> np.ndarray:
        """Accelerations that bring the commanded tip twist to a proportional approach of the goal."""
        env, c = self.env, self.env.task_spec.actions
        qd = np.clip(3.0 * err, -1.0, 1.0)
        qd[2] = np.clip(3.0 * err[2], -0.05, 0.05)
        mujoco.mj_jacBody(env.model, env.data, self.jacp, self.jacr, env.actions.body)
        want = np.concatenate([self.jacp[:, :4] @ qd[:4], self.jacr[:, :4] @ qd[:4]])
        acc = (want - env.actions.twist) / env.dt
        a = np.concatenate([acc[:3] / c.max_accel, acc[3:] / c.max_ang_accel, [qd[4] / c.max_cable_rate]])
        if np.abs(err).max() < 1e-3:
            self.waiting += 1
        return np.clip(a, -1.0, 1.0).astype(np.float32)


def run_expert_episode(env, seed: int | None = None, max_steps: int | None = None) -> dict:
    """Roll out the expert for one episode; return its totals."""
    expert = ScriptedExpert(env)
    obs, info = env.reset(seed=seed)
    total, steps = 0.0, 0
    limit = max_steps or math.inf
    while steps < limit:
        obs, r, term, trunc, info = env.step(expert.act(obs))
        total += r
        steps += 1
        if term or trunc:
            break
    return {
        "return": total,
        "steps": steps,
        "subtasks": info["subtask"],
        "subtasks_total": info["subtasks_total"],
        "success": info["success"],
        "time": info["time"],
    }
