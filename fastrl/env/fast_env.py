"""The FAST task as a gymnasium.Env: a thin shell over a family's Task, with the reward and observation terms."""

from __future__ import annotations

import math
from functools import partial

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces

from ..model.compiler import CompiledTask, compile_task
from ..spec.models import TaskSpec
from ..terms import OBSERVATION_TERMS, REWARD_FEATURES
from .families import family_of
from .images import EndoscopeFrames
from .task import GREEN, Task

__all__ = ["GREEN", "FastEnv"]


class FastEnv(gym.Env):
    """An arthroscope through a portal of a compiled FAST task; `family` (the spec's, by default) runs its episodes.

    `task` is the compiled model and its handles; `family` the Task that resets, senses and terminates; `state`
    the record the terms read. The env steps the physics, weighs the reward features and stacks observations.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(
        self,
        spec: TaskSpec,
        render_mode: str | None = None,
        width: int = 128,
        height: int = 128,
        *,
        late_starts: float = 0.0,
        later_subtasks: float = 0.0,
        recorded: tuple = (),
        recorded_starts: float = 0.0,
        family: type[Task] | None = None,
    ):
        self.task_spec = spec
        self.late_starts = late_starts  # unseeded resets (a vector env's next episodes) start up to this share late
        self.later_subtasks = later_subtasks  # and this share of them at a random later subtask
        self.recorded = tuple(recorded)  # (seed, portal) of recordings whose states unseeded resets may start at
        self.recorded_starts = recorded_starts if self.recorded else 0.0  # the share of them that do
        self._recorded_lengths: dict[int, int] = {}
        self._scratch: FastEnv | None = None
        self.task: CompiledTask = compile_task(spec)
        self.model, self.data = self.task.model, mujoco.MjData(self.task.model)
        self.render_mode, self.width, self.height = render_mode, width, height
        ep = spec.episode
        self.dt, self.substeps = 1.0 / ep.control_hz, ep.substeps
        self.max_steps = int(round(ep.time_limit * ep.control_hz))
        self.feature_names = list(spec.reward.features)
        self.feature_fns = [
            partial(REWARD_FEATURES[n].fn, **spec.reward.features[n].params)
            if spec.reward.features[n].params
            else REWARD_FEATURES[n].fn
            for n in self.feature_names
        ]
        self.weights = [float(spec.reward.features[n].weight) for n in self.feature_names]
        rays = any("rays" in REWARD_FEATURES[n].needs for n in self.feature_names)
        make = family or family_of(spec)
        self.family = make(compiled=self.task, data=self.data, max_steps=self.max_steps, rays=rays)
        self.state, self.actions = self.family.state, self.family.actions
        self.action_space = self.actions.space
        self.obs_fns = [OBSERVATION_TERMS[n].fn for n in spec.observation.terms()]
        coords = [i.coordinates for i in spec.instruments]
        self.obs_dim = sum(OBSERVATION_TERMS[n].width(coords) for n in spec.observation.terms())
        self.stack = spec.observation.stack
        state_space = spaces.Box(-np.inf, np.inf, (self.obs_dim * self.stack,), np.float32)
        image = spec.observation.image
        self.frames = None if image is None else EndoscopeFrames(task=self.task, model=self.model, image=image)
        if self.recorded_starts and image is not None:
            raise ValueError("recorded starts replay state observations only, not endoscope images")
        if self.frames is None:
            self.observation_space = state_space
        else:
            pixels = spaces.Box(0, 255, self.frames.shape, np.uint8)
            self.observation_space = spaces.Dict({"image": pixels, "state": state_space}) if image.state else pixels
        self.lens, self.cable = self.task.lens_qadr, int(self.task.qadr[4])
        self.steps = 0
        self._renderer = None
        self._frames = np.zeros((self.stack, self.obs_dim), np.float32)

    # ---- gymnasium API -------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: the family's start (pose, noise, targets, cue), then the clock and the observation."""
        super().reset(seed=seed)
        options = options or {}
        if self.frames is not None:
            self.frames.reset(seed)
        self.steps = 0
        if self.recorded_starts and seed is None and not options and self.np_random.random() < self.recorded_starts:
            self._start_recorded()
            return self.observation(), self._info([0.0] * len(self.feature_names))
        self.family.initialize_episode(self.np_random, options)
        if self.later_subtasks and seed is None and not options and self.state.subtasks_total > 1:
            if self.np_random.random() < self.later_subtasks:
                self.family.start_at(int(self.np_random.integers(1, self.state.subtasks_total)))
        if self.late_starts and seed is None and not options:
            self.steps = int(self.np_random.integers(0, int(self.late_starts * self.max_steps) + 1))
            self.state.time = self.steps * self.dt
        obs = self._observe(first=True)
        return obs, self._info([0.0] * len(self.feature_names))

    def step(self, action):
        """Apply one action for 1/control_hz seconds of physics and score the new state."""
        m, d = self.model, self.data
        self.family.before_step(action)
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
        self.family.place_recorded(portal, instruments, bodies)
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
        return self.family.body_poses()

    def set_portal_coordinates(self, q) -> None:
        """Place the scope at portal coordinates, at rest, with the servos holding there."""
        self.family.place(np.asarray(q, float))
        self.family.sense(first=True)

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
        from .render import new_renderer, render_views

        if self._renderer is None:
            self._renderer = new_renderer(self.model, self.height, self.width)
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
        self.family.copy_from(other.family)
        self.steps = other.steps
        self._frames[:] = other._frames
        if self.frames is not None:
            self.frames.frames[:] = other.frames.frames

    def _start_recorded(self) -> None:
        """Continue a random recording at a random step before it ends or the task does (a training start)."""
        i = int(self.np_random.integers(len(self.recorded)))
        if i not in self._recorded_lengths:
            self._recorded_lengths[i] = self._replay_recorded(i, None)
        self._replay_recorded(i, int(self.np_random.integers(self._recorded_lengths[i])))
        self.copy_state_from(self._scratch)

    def _replay_recorded(self, i: int, upto: int | None) -> int:
        """Replay recording i in the scratch env up to sample `upto` (None: all); return the samples replayed
        before the task ended or the time limit came."""
        if self._scratch is None:
            self._scratch = FastEnv(self.task_spec, family=type(self.family))
        seed, portal = self.recorded[i]
        scratch, n = self._scratch, min(len(portal), self.max_steps) if upto is None else upto + 1
        scratch.reset(seed=seed, options={"portal": portal[0]})
        for k in range(1, n):
            if scratch.replay_step(portal[k])[2]:
                return k
        return n

    # ---- the family's, for the expert, trainees and replay -------------------------------
    @property
    def subtask(self) -> int:
        """Subtasks completed so far."""
        return self.family.done_count

    done_count = subtask

    @property
    def target(self) -> list:
        """Servo targets: the scope's 5 coordinates, then the instruments'."""
        return self.family.target

    @target.setter
    def target(self, value: list) -> None:
        self.family.target = value

    @property
    def loose(self):
        """The loose bodies of a grasping task (None for other families)."""
        return self.family.loose

    t_pos = property(lambda self: self.family.t_pos, doc="This episode's target positions (N, 3).")
    t_fwd = property(lambda self: self.family.t_fwd, doc="This episode's target forward vectors (N, 3).")
    t_up = property(lambda self: self.family.t_up, doc="This episode's target up vectors (N, 3).")

    # ---- internals -----------------------------------------------------------------------
    def _advance(self):
        """Sense, update the cue, score the features; then the family moves on (or terminates)."""
        s, family = self.state, self.family
        self.steps += 1
        s.time = self.steps * self.dt
        family.after_step()
        vals = [fn(s) for fn in self.feature_fns]
        reward = sum([w * v for w, v in zip(self.weights, vals)])
        terminated = family.get_termination()
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
        return self._with_image(state, self.frames.observe(self.data, self.family.done_count, first))

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
        s, done, total = self.state, self.family.done_count, len(self.task.targets)
        return {
            "features": dict(zip(self.feature_names, vals)),
            "subtask": done,
            "subtasks_total": total,
            "cue": self.family.cue(),
            "success": done >= total,
            "contacts": s.contacts,
            "time": s.time,
        }
