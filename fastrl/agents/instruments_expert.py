"""The scripted expert of tasks with instruments: the scope's expert for the view, closed-form aiming for each tool."""

from __future__ import annotations

import math

import numpy as np

from ..env.instrument_actions import SCOPE_BOX, SCOPE_DISCRETE
from ..model.instruments import aim

PIVOT_SAFE = 0.045  # insertion (m) at which the tip pivots clear of the shell and the plate
AIMED = math.radians(1.0)  # pitch and yaw within this of the aim: go in
SHORT = 0.001  # the tip stops this far short of the target centre
REAIM = 0.01  # the scope's view is solved again once its target moved this far (m)
ABOVE_CUP = 0.03  # the grasper lets go this high above the cup's floor (m)


class TwoInstrumentExpert:
    """Drives the scope to the view of the current target and the working instrument's tip onto it."""

    def __init__(self, env, scope_expert):
        self.env, self.scope = env.unwrapped, scope_expert
        self.scope.level = bool((self.env.task.targets.horizon < math.pi).any())  # no roll for an unchecked horizon
        self.mode = self.env.task_spec.actions.mode
        self.tool = self.env.task.instruments[0]
        self.turn, self.view_at = 0, None

    def reset(self) -> None:
        """Forget the scope's goal (call after env.reset)."""
        self.scope.reset()
        self.turn, self.view_at = 0, None

    def act(self, obs=None):
        """Next action: scope and instrument take turns; either takes the other's turn when it has nothing to do."""
        env = self.env
        if env.steps == 0:
            self.reset()
        k = min(env.done_count, len(env.t_pos) - 1)
        if self.view_at is None or np.linalg.norm(env.t_pos[k] - self.view_at) > REAIM:  # the target moved
            self.scope.goal_for, self.view_at = -1, env.t_pos[k].copy()
        scope_err = self.scope.error(env.portal_coordinates(), k)
        tool_err = self.grasper_error(k) if env.loose is not None else self.tool_error(env.t_pos[k])
        self.turn += 1
        if self.mode == "discrete":
            return self._discrete(scope_err, tool_err)
        scope = self.scope.to_action(scope_err)
        step = env.actions.instrument_step
        tool = np.clip(0.5 * tool_err / step, -1.0, 1.0)
        return np.concatenate([np.asarray(scope, np.float32).reshape(SCOPE_BOX[self.mode]), tool]).astype(np.float32)

    def tool_error(self, target: np.ndarray, back: float = SHORT) -> np.ndarray:
        """Goal minus the instrument's coordinates: pivot at a safe depth onto the line to the target, then go in."""
        t, env = self.tool, self.env
        q = env.data.qpos[t.qadr].copy()
        goal = q.copy()
        goal[:3] = aim(t.point, t.rot, target, back)
        if max(abs(goal[0] - q[0]), abs(goal[1] - q[1])) > AIMED:
            goal[2] = min(goal[2], PIVOT_SAFE, q[2])
        return goal - q

    def grasper_error(self, k: int) -> np.ndarray:
        """Goal minus the grasper's coordinates: open onto body k, close on it, carry it over the cup, let go."""
        t, env, loose = self.tool, self.env, self.env.loose
        q = env.data.qpos[t.qadr].copy()
        tip = env.data.xpos[t.tip_body]
        widest = t.ranges[4, 1]
        if loose.held == k:
            over = loose.cup + np.array([0.0, 0.0, ABOVE_CUP])
            err = self.tool_error(over, back=0.0)
            err[4] = (widest if np.linalg.norm(over - tip) < 0.006 else 0.0) - q[4]
            return err
        if loose.in_cup(env.data, k):  # dropped: open, back off
            err = np.zeros(5)
            err[2] = min(0.0, PIVOT_SAFE - q[2])
            return err
        body = env.data.xpos[loose.bodies[k]]
        err = self.tool_error(body, back=0.0)
        near = np.linalg.norm(body - tip) < 0.003
        err[4] = (0.0 if near and q[4] > 0.5 * widest else widest if not near else 0.0) - q[4]
        if not near:
            err[2] = err[2] if q[4] > 0.8 * widest else min(err[2], 0.0)  # open before going in
        return err

    def _discrete(self, scope_err: np.ndarray, tool_err: np.ndarray) -> int:
        """One increment: the scope's or the instrument's largest, alternating."""
        step = self.env.actions.instrument_step
        ratio = tool_err / step
        j = int(np.argmax(np.abs(ratio)))
        tool = SCOPE_DISCRETE + 2 * j + (0 if tool_err[j] > 0 else 1) if abs(ratio[j]) > 0.6 else 0
        if ratio[2] < -0.6:  # retract before pivoting
            tool = SCOPE_DISCRETE + 5
        scope = self.scope.to_action(scope_err)
        if self.turn % 2 and tool:
            return tool
        return scope or tool
