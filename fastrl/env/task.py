"""The Task of a family (dm_control's Task): its episode's reset, actions, sensing, cue machine and termination."""

from __future__ import annotations

import math
from functools import partial

import mujoco
import numpy as np

from ..model.compiler import CompiledTask
from ..terms import RESET_TERMS, TERMINATION_TERMS, EpisodeStart
from ..terms.state import TaskState
from .actions import ContinuousActions, DiscreteActions, RateActions
from .cues import cue_checks, cue_green, update_dwell
from .sensing import Sensor

ACTIVE, GREEN, DONE, HIDDEN = (1.0, 0.55, 0.1, 1.0), (0.1, 0.85, 0.2, 1.0), (0.3, 0.5, 1.0, 0.6), (0, 0, 0, 0)


class Task:
    """The scope through its portal viewing each target in turn; the families add to it. Fills its own `state`.

    An episode: `initialize_episode` (the spec's start changed by its reset terms), then per step `before_step`
    (servo targets), the physics (the env's), `after_step` (sense, cue), the reward (the env's, from `state`) and
    `get_termination` (the next subtask, then the spec's termination terms).
    """

    State = TaskState
    loose = None  # the loose bodies of a grasping task
    reads_past = True  # measured poses may read an avatar passed when the next one is held (green: the view's alone)

    def __init__(self, *, compiled: CompiledTask, data: mujoco.MjData, max_steps: int, rays: bool):
        spec, self.compiled, self.model, self.data = compiled.spec, compiled, compiled.model, data
        self.dt = 1.0 / spec.episode.control_hz
        ranges = compiled.ranges
        self.actions = self.make_actions()
        self.sensor = Sensor(compiled, rays)
        self.sensor.bind(data)
        s = self.state = self.State()
        s.dt, s.gamma, s.fov = self.dt, spec.reward.gamma, math.radians(spec.scope.fov_deg)
        s.portal_lo, s.portal_hi = tuple(ranges[:, 0].tolist()), tuple(ranges[:, 1].tolist())
        s.subtasks_total = len(compiled.targets)
        s.time_limit = max_steps * self.dt
        t = compiled.targets
        self.t_pos, self.t_fwd, self.t_up, self.t_quat = t.pos.copy(), t.fwd.copy(), t.up.copy(), t.quat.copy()
        self.target = [0.0] * self.model.nu  # servo targets: the scope's 5 coordinates, then the instruments'
        self.done_count, self.elapsed, self.was_green, self.positions_only = 0, 0.0, False, False
        self.read_past_now, self.ahead, self.passed = False, 0.0, False  # a replay of measured poses: read_past
        declared = spec.episode
        self.resets = [
            _bound(term, declared.resets[name]) for name, term in RESET_TERMS.items() if name in declared.resets
        ]
        self.terminations = [_bound(TERMINATION_TERMS[name], params) for name, params in declared.terminations.items()]

    def make_actions(self):
        """The scope's actions in the spec's mode."""
        cfg, ranges = self.compiled.spec.actions, self.compiled.ranges
        if cfg.mode == "discrete":
            return DiscreteActions(cfg, ranges)
        if cfg.mode == "rates":
            return RateActions(cfg, ranges, self.dt)
        return ContinuousActions(cfg, ranges, self.dt, self.model.body("scope_optics").id)

    # ---- an episode ----------------------------------------------------------------------
    def initialize_episode(self, rng: np.random.Generator, options: dict) -> None:
        """The spec's start changed by its reset terms (options may give poses), placed; cue and state read there."""
        start = self.episode_start(options)
        for apply in self.resets:
            apply(start, rng)
        self.episode_targets(start)
        self.done_count, self.elapsed = 0, 0.0
        self.read_past_now = self.reads_past and bool(options.get("read_past"))
        self.ahead, self.passed = 0.0, False
        self.place_start(start, options)
        self.actions.reset(self.data, self.compiled.qadr)
        s = self.state
        s.time, s.dwell, s.prev_dwell, s.dwell_best, s.potential = 0.0, 0.0, 0.0, 0.0, 0.0
        s.subtasks_done = 0
        self.select(0)
        self.sense(first=True)
        s.green = cue_green(s)
        s.completed = False
        self.paint()

    def start_at(self, k: int) -> None:
        """After initialize_episode: make subtask k current, the ones before it done (a training start)."""
        s = self.state
        self.done_count = s.subtasks_done = k
        self.make_current(k)
        s.prev_potential = s.potential
        self.paint()

    def episode_start(self, options: dict) -> EpisodeStart:
        """The spec's start before the reset terms: avatars where the spec puts them, the scope at its start pose."""
        t = self.compiled.targets
        given = options.get("portal") is not None
        return EpisodeStart(
            at=t.at.copy(), on_plate=t.on_plate, scope=None if given else self.start_pose(), instruments=None
        )

    def episode_targets(self, start: EpisodeStart) -> None:
        """This episode's target poses: the spec's (a family whose targets move overrides this)."""
        t = self.compiled.targets
        self.t_pos[:], self.t_fwd[:], self.t_up[:], self.t_quat[:] = t.pos, t.fwd, t.up, t.quat

    def start_pose(self) -> np.ndarray:
        """The spec's start pose of the scope."""
        st = self.compiled.spec.scope.start
        return np.array(
            [
                math.radians(st.pitch_deg),
                math.radians(st.yaw_deg),
                st.insertion,
                math.radians(st.roll_deg),
                math.radians(st.cable_deg),
            ]
        )

    def place_start(self, start: EpisodeStart, options: dict) -> None:
        """Put the scope (and what a family adds) at its start (the options' pose, where they give one)."""
        self.place(np.asarray(options["portal"], float) if start.scope is None else start.scope)

    def before_step(self, action) -> None:
        """Servo targets and controls for an action (after a replayed pose, complete it first)."""
        m, d = self.model, self.data
        if self.positions_only:
            mujoco.mj_forward(m, d)
            self.positions_only = False
        self.target = self.actions.targets(action, self.target, self.state.portal, m, d)
        d.ctrl[:] = self.target

    def after_step(self) -> None:
        """Sense the new pose and update the cue: green, dwell fill, completion."""
        self.sense(first=False)
        self.was_green = self.state.green
        self.elapsed = update_dwell(self.state, self.elapsed, self.dt)
        if self.read_past_now:
            self.read_past()

    def read_past(self) -> None:
        """Replay of measured poses (read off video frames, imported from a tracker): the next avatar's dwell held
        while this one is current completes both. Their error can lose a hold the trainee made (the scripted
        expert's holds lie within a degree of TraceLines' 6 degree cue), and the avatars are ordered: read as the
        live task reads them, one lost hold loses every avatar after it. Poses given as they were (the simulator's,
        an agent's, a cohort's) replay by the live task's rule."""
        s, k = self.state, self.done_count
        ahead = k + 1 < len(self.t_pos) and self.sensor.green_on(
            s, k + 1, tuple(self.t_pos[k + 1].tolist()), tuple(self.t_up[k + 1].tolist())
        )
        self.ahead = self.ahead + self.dt if ahead else 0.0
        self.passed = ahead and not s.completed and self.ahead >= self.compiled.targets.dwell[k + 1] - 1e-9
        if self.passed:
            s.completed = True

    def get_termination(self) -> bool:
        """After the reward: the cue moves on to the next target; then whether a declared termination holds."""
        self.next_subtask()
        s = self.state
        return any(term(s) for term in self.terminations)

    def next_subtask(self) -> None:
        """On a completed subtask make the next target current (none after the last); repaint where the cue changed."""
        s = self.state
        if not s.completed:
            if s.green != self.was_green:
                self.paint()
            return
        self.done_count += 2 if self.passed else 1
        s.subtasks_done = self.done_count
        self.elapsed, self.ahead, self.passed = 0.0, 0.0, False
        if self.done_count < len(self.t_pos):
            self.make_current(self.done_count)
        self.paint()

    def make_current(self, k: int) -> None:
        """Subtask k becomes the cue's target, its dwell bar empty."""
        s = self.state
        self.select(k)
        self.retarget()
        s.dwell = s.prev_dwell = s.dwell_best = 0.0
        s.green = cue_green(s)

    def cue(self) -> dict:
        """The cue as the info reports it."""
        s = self.state
        c, h, d = cue_checks(s)
        return {"centring": c, "horizon": h, "distance": d, "green": s.green, "dwell": s.dwell}

    # ---- sensing and placing -------------------------------------------------------------
    def sense(self, first: bool) -> None:
        """Read the scope into the state."""
        self.sensor.read(self.state, self.model, self.data, first=first)

    def retarget(self) -> None:
        """The target-dependent quantities, after the target changed."""
        self.sensor.errors(self.state, self.model, self.data)

    def select(self, k: int) -> None:
        """Make subtask k current."""
        s = self.state
        self.sensor.set_target(s, k, self.t_pos[k], self.t_fwd[k], self.t_up[k], self.t_quat[k])
        s.goals = self.t_pos[min(k + 1, len(self.t_pos) - 1)]

    def place(self, q: np.ndarray, positions_only: bool = False) -> None:
        """Set the portal joints to q (clipped to their ranges), at rest, and recompute positions.

        positions_only (replay): kinematics and contacts only; a later step needs the full mj_forward.
        """
        if q.shape != (5,) or not np.isfinite(q).all():
            raise ValueError(f"portal coordinates must be 5 finite numbers, got {q!r}")
        ct, m, d = self.compiled, self.model, self.data
        q = np.minimum(np.maximum(q, ct.ranges[:, 0]), ct.ranges[:, 1])
        d.qpos[ct.qadr] = q
        d.qpos[ct.lens_qadr] = -q[4]
        d.qvel[:] = 0.0
        d.ctrl[:5] = q
        self.target = q.tolist() + self.target[5:]  # the instruments' servos keep their targets
        self.positions_only = positions_only
        (mujoco.mj_fwdPosition if positions_only else mujoco.mj_forward)(m, d)

    def place_recorded(self, portal, instruments=None, bodies=None) -> None:
        """Replay: put the scope (and what a family adds) at recorded coordinates."""
        self.place(np.asarray(portal, float), positions_only=True)

    def paint(self) -> None:
        """Colour avatars by cue state: done, active (orange or green), hidden."""
        rgba = self.model.geom_rgba
        k, line = self.done_count, self.compiled.targets.line
        for i, (disk, mark) in enumerate(self.compiled.avatar_geoms):
            colour = DONE if i < k else (GREEN if self.state.green else ACTIVE) if i == k else HIDDEN
            if i < k and line is None:
                colour = HIDDEN
            rgba[disk] = colour
            rgba[mark, 3] = colour[3] if i >= k else 0.0

    def copy_from(self, other: Task) -> None:
        """Continue from another task of the same family: state, cue, servo targets, avatars, action state."""
        self.state.copy_from(other.state)
        self.done_count, self.elapsed, self.was_green = other.done_count, other.elapsed, other.was_green
        self.target, self.positions_only = list(other.target), other.positions_only
        for mine, theirs in zip(self.poses(), other.poses()):
            mine[:] = theirs
        self.actions.copy_from(other.actions)

    def body_poses(self) -> np.ndarray | None:
        """Free bodies' poses (k, 7); None for a family without them."""
        return None

    def poses(self) -> tuple[np.ndarray, ...]:
        """This episode's target poses: positions, forward and up vectors, quaternions."""
        return self.t_pos, self.t_fwd, self.t_up, self.t_quat


def _bound(term, params: dict):
    """A term's function with the spec's parameters bound (the bare function where there are none)."""
    return partial(term.fn, **params) if params else term.fn
