"""The FAST task as a gymnasium.Env: portal actions, cue machine, observation and reward terms."""

from __future__ import annotations

import math
from functools import partial

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from ..model.compiler import CompiledTask, compile_task
from ..spec import geometry as geo
from ..spec.models import TaskSpec
from ..terms import OBSERVATION_TERMS, REWARD_FEATURES, TaskState
from .actions import ContinuousActions, DiscreteActions, RateActions
from .cues import cue_checks, cue_green, update_dwell
from .images import EndoscopeFrames
from .loose_sensing import LooseBodies
from .sensing import Sensor
from .tool_actions import ToolActions
from .tool_sensing import ToolSensor, place_tools, tool_start

ACTIVE, GREEN, DONE, HIDDEN = (1.0, 0.55, 0.1, 1.0), (0.1, 0.85, 0.2, 1.0), (0.3, 0.5, 1.0, 0.6), (0, 0, 0, 0)


class FastEnv(gym.Env):
    """An arthroscope through a portal of a compiled FAST task."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(
        self,
        spec: TaskSpec,
        render_mode: str | None = None,
        width: int = 128,
        height: int = 128,
        *,
        late_starts: float = 0.0,
    ):
        self.task_spec = spec
        self.late_starts = late_starts  # unseeded resets (a vector env's next episodes) start up to this share late
        self.task: CompiledTask = compile_task(spec)
        self.model, self.data = self.task.model, mujoco.MjData(self.task.model)
        self.render_mode, self.width, self.height = render_mode, width, height
        ep = spec.episode
        self.dt, self.substeps = 1.0 / ep.control_hz, ep.substeps
        self.max_steps = int(round(ep.time_limit * ep.control_hz))
        ranges = self.task.ranges
        if spec.actions.mode == "discrete":
            self.actions = DiscreteActions(spec.actions, ranges)
        elif spec.actions.mode == "rates":
            self.actions = RateActions(spec.actions, ranges, self.dt)
        else:
            self.actions = ContinuousActions(spec.actions, ranges, self.dt, self.model.body("scope_optics").id)
        self.tools = ToolSensor(self.task) if self.task.instruments else None
        self.loose = LooseBodies(self.task) if spec.task.bodies else None
        if self.tools is not None:
            self.actions = ToolActions(self.actions, spec.actions, self.task.instruments, self.dt)
        self.action_space = self.actions.space
        self.feature_names = list(spec.reward.features)
        self.feature_fns = [
            partial(REWARD_FEATURES[n].fn, **spec.reward.features[n].params)
            if spec.reward.features[n].params
            else REWARD_FEATURES[n].fn
            for n in self.feature_names
        ]
        self.weights = [float(spec.reward.features[n].weight) for n in self.feature_names]
        self.obs_fns = [OBSERVATION_TERMS[n].fn for n in spec.observation.terms()]
        coords = [i.coordinates for i in spec.instruments]
        self.obs_dim = sum(OBSERVATION_TERMS[n].width(coords) for n in spec.observation.terms())
        self.stack = spec.observation.stack
        state_space = spaces.Box(-np.inf, np.inf, (self.obs_dim * self.stack,), np.float32)
        image = spec.observation.image
        self.frames = None if image is None else EndoscopeFrames(task=self.task, model=self.model, image=image)
        if self.frames is None:
            self.observation_space = state_space
        else:
            pixels = spaces.Box(0, 255, self.frames.shape, np.uint8)
            self.observation_space = spaces.Dict({"image": pixels, "state": state_space}) if image.state else pixels
        rays = any("rays" in REWARD_FEATURES[n].needs for n in self.feature_names)
        self.sensor = Sensor(self.task, rays)
        self.sensor.bind(self.data)
        self.state = TaskState()
        self.state.dt, self.state.gamma = self.dt, spec.reward.gamma
        self.state.fov = math.radians(spec.scope.fov_deg)
        self.state.portal_lo, self.state.portal_hi = tuple(ranges[:, 0].tolist()), tuple(ranges[:, 1].tolist())
        self.state.subtasks_total = len(self.task.targets)
        self.state.time_limit = self.max_steps * self.dt
        self.lens, self.cable = self.task.lens_qadr, int(self.task.qadr[4])
        self._renderer = None
        self._positions_only = False
        self.target = [0.0] * self.model.nu  # servo targets: the scope's 5 coordinates, then the instruments'
        self._frames = np.zeros((self.stack, self.obs_dim), np.float32)
        self._reset_targets()

    # ---- gymnasium API -------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: start pose (with its noise), avatars (with their jitter), cue state."""
        super().reset(seed=seed)
        options = options or {}
        self._reset_targets(jitter=True)
        if self.frames is not None:
            self.frames.reset(seed)
        q0 = options.get("portal")
        if q0 is None:
            q0 = self._start_pose()
        self.steps, self.done_count, self.elapsed = 0, 0, 0.0
        if self.loose is not None:
            self.loose.reset(self.data)
        self._place(np.asarray(q0, float))
        if self.tools is not None:
            tq = options.get("instruments")
            self._place_tools(tool_start(self.task, self.np_random) if tq is None else np.asarray(tq, float))
        if self.loose is not None and options.get("bodies") is not None:
            self.loose.place(self.data, options["bodies"])
            mujoco.mj_forward(self.model, self.data)
        self.actions.reset(self.data, self.task.qadr)
        s = self.state
        s.time, s.dwell, s.prev_dwell, s.dwell_best, s.potential = 0.0, 0.0, 0.0, 0.0, 0.0
        if self.late_starts and seed is None and not options:
            self.steps = int(self.np_random.integers(0, int(self.late_starts * self.max_steps) + 1))
            s.time = self.steps * self.dt
        self._select(0)
        self._read(first=True)
        s.green = cue_green(s)
        s.completed = False
        self._paint()
        obs = self._observe(first=True)
        return obs, self._info([0.0] * len(self.feature_names))

    def step(self, action):
        """Apply one action for 1/control_hz seconds of physics and score the new state."""
        m, d = self.model, self.data
        if self._positions_only:  # the last pose came from replay: complete mj_forward before stepping
            mujoco.mj_forward(m, d)
            self._positions_only = False
        self.target = self.actions.targets(action, self.target, self.state.portal, m, d)
        d.ctrl[:] = self.target
        mujoco.mj_step2(m, d)
        if self.substeps > 1:
            mujoco.mj_step(m, d, nstep=self.substeps - 1)
        d.qpos[self.lens] = -d.qpos[self.cable]  # remove the soft coupling's drift: replay is then exact
        mujoco.mj_step1(m, d)
        if not math.isfinite(d.qpos[0]):
            raise RuntimeError("physics diverged (non-finite state)")
        return self._advance()

    def replay_step(self, portal, instruments=None, bodies=None):
        """Place the scope (instruments, loose bodies) at recorded coordinates and score it like a step (replay)."""
        if self.loose is not None and bodies is not None:
            self.loose.place(self.data, bodies)
        self._place(np.asarray(portal, float), positions_only=True)
        if self.tools is not None and instruments is not None:
            self._place_tools(np.asarray(instruments, float), positions_only=True)
        return self._advance()

    def render(self):
        """The endoscope image (H, W, 3) uint8."""
        return self.render_views(outside=False)["endoscope"]

    def close(self):
        """Free the renderers."""
        if self.frames is not None:
            self.frames.close()
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ---- public helpers ------------------------------------------------------------------
    def portal_coordinates(self) -> np.ndarray:
        """Current [pitch, yaw, insertion, roll, cable] (rad, rad, m, rad, rad)."""
        return self.data.qpos[self.task.qadr].copy()

    def instrument_coordinates(self) -> np.ndarray:
        """Every instrument's portal coordinates, in spec order (empty without instruments)."""
        return np.concatenate([self.data.qpos[t.qadr] for t in self.task.instruments] or [np.zeros(0)])

    def body_poses(self) -> np.ndarray | None:
        """LooseBodies' free bodies, (k, 7) position and quaternion (wxyz); None for other tasks."""
        return None if self.loose is None else self.loose.poses(self.data)

    def set_portal_coordinates(self, q) -> None:
        """Place the scope at portal coordinates, at rest, with the servos holding there."""
        self._place(np.asarray(q, float))
        self._read(first=True)

    def set_reward_weights(self, weights: dict[str, float]) -> None:
        """Change feature weights while running; names must be features of the spec."""
        unknown = sorted(set(weights) - set(self.feature_names))
        if unknown:
            raise ValueError(f"unknown reward features {unknown}; this env has {self.feature_names}")
        for name, w in weights.items():
            self.weights[self.feature_names.index(name)] = float(w)

    def reward_weights(self) -> dict[str, float]:
        """Current feature weights."""
        return dict(zip(self.feature_names, self.weights))

    def render_views(self, outside: bool = True) -> dict[str, np.ndarray]:
        """Endoscope image and, if asked, an outside view with the shell hidden."""
        from .render import render_views

        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, self.height, self.width)
        return render_views(self._renderer, self.model, self.data, self.task, outside)

    def hold_here(self) -> None:
        """Servo targets to the current pose: the scope stays where an outside force (a mouse pull) left it."""
        self.target = self.portal_coordinates().tolist() + self.target[5:]

    def observation(self):
        """The current observation, without advancing the frame stacks."""
        state = self._state() if self.stack == 1 else self._frames.reshape(-1).copy()
        return state if self.frames is None else self._with_image(state, self.frames.frames.copy())

    def copy_state_from(self, other: FastEnv) -> None:
        """Continue from another env of the same task: physics, servo targets, cue state, avatars, frames."""
        mujoco.mj_copyData(self.data, self.model, other.data)
        for name in TaskState.__slots__:
            setattr(self.state, name, getattr(other.state, name))
        self.steps, self.done_count, self.elapsed = other.steps, other.done_count, other.elapsed
        self.target = list(other.target)
        self._positions_only = other._positions_only
        self._frames[:] = other._frames
        if self.frames is not None:
            self.frames.frames[:] = other.frames.frames
        for name in ("t_pos", "t_fwd", "t_up", "t_quat"):
            getattr(self, name)[:] = getattr(other, name)
        if hasattr(other.actions, "twist"):
            self.actions.twist[:] = other.actions.twist

    @property
    def subtask(self) -> int:
        """Subtasks completed so far."""
        return self.done_count

    # ---- internals -----------------------------------------------------------------------
    def _advance(self):
        """Update state, cues, reward and subtask after the pose changed."""
        s = self.state
        self.steps += 1
        s.time = self.steps * self.dt
        self._read(first=False)
        was_green = s.green
        self.elapsed = update_dwell(s, self.elapsed, self.dt)
        vals = [fn(s) for fn in self.feature_fns]
        reward = sum(w * v for w, v in zip(self.weights, vals))
        terminated = False
        if s.completed:
            self.done_count += 1
            self.elapsed = 0.0
            terminated = self.done_count >= len(self.task.targets)
            if not terminated:
                self._select(self.done_count)
                self.sensor.errors(s, self.model, self.data)
                if self.tools is not None:
                    self.tools.errors(s, self.model, self.data)
                s.dwell = s.prev_dwell = s.dwell_best = 0.0
                s.green = cue_green(s)
            self._paint()
        elif s.green != was_green:
            self._paint()
        truncated = not terminated and self.steps >= self.max_steps
        return self._observe(), reward, terminated, truncated, self._info(vals)

    def _observe(self, first: bool = False):
        """Concatenate the observation terms and stack them if asked; with images, render and stack a frame."""
        frame = self._state()
        if self.stack == 1:
            state = frame
        else:
            if first:
                self._frames[:] = frame
            else:
                self._frames[:-1] = self._frames[1:]
                self._frames[-1] = frame
            state = self._frames.reshape(-1).copy()
        if self.frames is None:
            return state
        return self._with_image(state, self.frames.observe(self.data, self.done_count, first))

    def _state(self) -> np.ndarray:
        """The observation terms of the current state, concatenated."""
        s = self.state
        values = []
        for f in self.obs_fns:
            values.extend(f(s))
        return np.array(values, np.float32)

    def _with_image(self, state: np.ndarray, image: np.ndarray):
        """The image alone, or a Dict of image and state, as the spec asks."""
        return {"image": image, "state": state} if self.task_spec.observation.image.state else image

    def _info(self, vals: list) -> dict:
        """Per-step info: features, subtask, cue, success."""
        s = self.state
        c, h, d = cue_checks(s)
        cue = {"centring": c, "horizon": h, "distance": d, "green": s.green, "dwell": s.dwell}
        if self.tools is not None:
            cue["touching"] = s.tool_touching
        return {
            "features": dict(zip(self.feature_names, vals)),
            "subtask": self.done_count,
            "subtasks_total": len(self.task.targets),
            "cue": cue,
            "success": self.done_count >= len(self.task.targets),
            "contacts": s.contacts,
            "time": s.time,
        }

    def _place(self, q: np.ndarray, positions_only: bool = False) -> None:
        """Set the portal joints to q (clipped to their ranges), at rest, and recompute positions.

        positions_only (replay): kinematics and contacts only; a later step() needs the full mj_forward.
        """
        if q.shape != (5,) or not np.isfinite(q).all():
            raise ValueError(f"portal coordinates must be 5 finite numbers, got {q!r}")
        q = np.minimum(np.maximum(q, self.task.ranges[:, 0]), self.task.ranges[:, 1])
        m, d = self.model, self.data
        d.qpos[self.task.qadr] = q
        d.qpos[self.task.lens_qadr] = -q[4]
        d.qvel[:] = 0.0
        d.ctrl[:5] = q
        self.target = q.tolist() + self.target[5:]  # the instruments' servos keep their targets
        self._positions_only = positions_only
        (mujoco.mj_fwdPosition if positions_only else mujoco.mj_forward)(m, d)

    def _place_tools(self, q: np.ndarray, positions_only: bool = False) -> None:
        """Set the instruments' coordinates at rest, servos holding there, and recompute positions."""
        n = sum(len(t.qadr) for t in self.task.instruments)
        if q.shape != (n,) or not np.isfinite(q).all():
            raise ValueError(f"instrument coordinates must be {n} finite numbers, got {q!r}")
        self.target = self.target[:5] + place_tools(self.task, self.data, q).tolist()
        self._positions_only = positions_only
        (mujoco.mj_fwdPosition if positions_only else mujoco.mj_forward)(self.model, self.data)

    def _read(self, first: bool) -> None:
        """Read the scope (and instruments) into the task state."""
        k = min(self.done_count, len(self.t_pos) - 1)
        if self.loose is not None:
            self.loose.update(self, k)
        self.sensor.read(self.state, self.model, self.data, first=first)
        if self.tools is not None:
            self.tools.read(self.state, self.model, self.data, first=first)
        if self.loose is not None:
            self.state.tool_ok = self.loose.done(self.state, self.data, k)
            self.loose.settle(self.state)

    def _start_pose(self) -> np.ndarray:
        """The spec's start pose plus its uniform noise."""
        st = self.task_spec.scope.start
        q = np.array(
            [
                math.radians(st.pitch_deg),
                math.radians(st.yaw_deg),
                st.insertion,
                math.radians(st.roll_deg),
                math.radians(st.cable_deg),
            ]
        )
        noise = np.array(st.noise) * np.array([math.pi / 180, math.pi / 180, 1.0, math.pi / 180, math.pi / 180])
        return q + self.np_random.uniform(-1.0, 1.0, 5) * noise

    def _reset_targets(self, jitter: bool = False) -> None:
        """Target poses for this episode: the spec's, moved by the task's jitter."""
        t = self.task.targets
        self.t_pos, self.t_fwd, self.t_up, self.t_quat = t.pos.copy(), t.fwd.copy(), t.up.copy(), t.quat.copy()
        jm, jd = self.task_spec.task.jitter
        if not jitter or (jm == 0 and jd == 0):
            return
        r = self.task_spec.scene.radius
        for i in range(len(t)):
            noise = self.np_random.uniform(-1.0, 1.0, 2)
            surface = "plate" if t.on_plate[i] else "dome"
            at = t.at[i] + noise * (jm if t.on_plate[i] else jd)
            pos, fwd, up = geo.avatar_pose(r, surface, at, t.heading[i])
            self.t_pos[i], self.t_fwd[i], self.t_up[i] = pos, fwd, up
            self.t_quat[i] = geo.mat_to_quat(geo.avatar_rotation(fwd, up))
            disk, mark = self.task.avatar_geoms[i]
            self.model.geom_pos[disk] = pos
            self.model.geom_pos[mark] = pos + 0.9 * t.size * up + 0.0002 * fwd
            self.model.geom_quat[disk] = self.model.geom_quat[mark] = self.t_quat[i]

    def _select(self, k: int) -> None:
        """Make subtask k current."""
        s = self.state
        self.sensor.set_target(s, k, self.t_pos[k], self.t_fwd[k], self.t_up[k], self.t_quat[k])
        nxt = min(k + 1, len(self.t_pos) - 1)
        s.goals = self.t_pos[nxt]

    def _paint(self) -> None:
        """Colour avatars by cue state: done, active (orange or green), hidden."""
        rgba = self.model.geom_rgba
        k = self.done_count
        for i, (disk, mark) in enumerate(self.task.avatar_geoms):
            colour = DONE if i < k else (GREEN if self.state.green else ACTIVE) if i == k else HIDDEN
            if i < k and self.task.targets.line is None:
                colour = HIDDEN
            rgba[disk] = colour
            rgba[mark, 3] = colour[3] if i >= k else 0.0
