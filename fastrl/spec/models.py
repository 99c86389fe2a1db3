"""The task-spec language: frozen pydantic models with every check a spec can fail."""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from . import geometry as geo
from .anatomy import landmark_pose
from .base import NonNeg, Pos, Strict, _fail, _raise
from .defaults import resolve_defaults
from .episode import Episode, episode_term_errors
from .instruments import Instrument, instrument_errors
from .irl import IRL, late_starts, learning_train, recorded_starts, starts_cloned, unobserved_terms
from .limits import MAX_LINE_POINTS, MAX_REPLAY_GB, MAX_SUBTASKS
from .loose import Cup, LooseBody, loose_errors
from .migrate import upgraded
from .reach import avatar_problem, portal_point, reach_problem
from .scenes import AbdomenScene, DomeScene, Organ, Portal, Scene  # noqa: F401 - Abdomen/Dome/Organ re-exported
from .shaft import Shaft
from .state_reward import Observation, Reward
from .study import Study
from .training import Evaluate, Train

DOME_KINDS = ("image_centring", "periscoping", "trace_lines")  # one scope, ordered avatars on a FAST dome


class StartPose(Strict):
    """Initial portal coordinates of the scope."""

    pitch_deg: float = 0.0
    yaw_deg: float = 0.0
    insertion: float = 0.03
    roll_deg: float = 0.0
    cable_deg: float = 0.0


class Scope(Shaft):
    """The arthroscope: shaft through a portal, camera at the tip, angled optics."""

    optics_deg: Literal[0, 30, 70] = 30
    fov_deg: float = Field(80.0, ge=20, le=140)
    start: StartPose = StartPose()


class Cue(Strict):
    """Tolerances under which an avatar turns green, and how long they must hold."""

    # at least a microdegree: the cue potential divides by them in radians, where a subnormal one rounds to 0
    centring_deg: float = Field(8.0, ge=1e-6, le=180)
    horizon_deg: float = Field(15.0, ge=1e-6, le=180)
    distance: tuple[Pos, Pos] = (0.02, 0.05)
    dwell: NonNeg = 0.5

    @field_validator("distance")
    @classmethod
    def _increasing(cls, v):
        if v[0] >= v[1]:
            raise ValueError(f"distance range must be increasing, got {list(v)}")
        return v


class Avatar(Strict):
    """A target on the plate (at = [x, y] m) or on the dome (at = [azimuth, elevation] deg)."""

    surface: Literal["plate", "dome"] = "plate"
    at: tuple[float, float]
    heading_deg: float = Field(
        90.0, description="direction of the avatar's up, deg (plate: from +x; dome: from the zenith)"
    )
    cue: Cue | None = None


class Line(Strict):
    """TraceLines' line on the plate; avatars are placed along it every `spacing` metres."""

    points: list[tuple[float, float]] = Field(min_length=2, max_length=MAX_LINE_POINTS)
    spline: bool = False
    spacing: float = Field(0.01, gt=0.002, le=0.1)
    width: float = Field(0.0015, gt=0, le=0.01)
    heading_deg: float = 90.0


def line_avatars(line: Line) -> int:
    """How many avatars a line places (one every `spacing` metres after its start)."""
    pts = np.asarray(line.points, float)
    dense = geo.catmull_rom(pts) if line.spline else pts
    return len(geo.sample_polyline(dense, line.spacing)) - 1


class Landmark(Strict):
    """An anatomical landmark to visualise: the point of an organ that faces the portal."""

    organ: str = Field(description="a name from scene.anatomy")
    cue: Cue | None = None


class Task(Strict):
    """Which task, its avatars, line or landmarks, and the default cue."""

    kind: Literal["image_centring", "periscoping", "trace_lines", "liver_tour", "triangulation", "loose_bodies"]
    avatars: list[Avatar] = Field([], max_length=MAX_SUBTASKS)
    line: Line | None = None
    landmarks: list[Landmark] = Field([], max_length=MAX_SUBTASKS)
    bodies: list[LooseBody] = Field([], max_length=MAX_SUBTASKS, description="loose_bodies: what to grasp")
    cup: Cup | None = Field(None, description="loose_bodies: where to drop them")
    cue: Cue = Cue()

    @model_validator(mode="after")
    def _targets(self):
        if self.kind == "trace_lines" and self.line is None:
            raise ValueError("trace_lines needs a 'line'")
        if self.line is not None:
            n = line_avatars(self.line)
            if n > MAX_SUBTASKS:
                spacing = self.line.spacing
                _fail("line", f"the line places {n:,} avatars {spacing:g} m apart, at most {MAX_SUBTASKS} are allowed")
        if self.kind == "liver_tour":
            if not self.landmarks:
                raise ValueError("liver_tour needs at least one landmark")
            if self.avatars or self.line is not None:
                raise ValueError("liver_tour has landmarks fixed to the anatomy: no avatars or line")
        elif self.kind not in ("trace_lines", "loose_bodies") and not self.avatars:
            raise ValueError(f"{self.kind} needs at least one avatar")
        return self


class Actions(Strict):
    """Action space and its scales."""

    mode: Literal["discrete", "continuous", "rates"] = Field(
        "discrete",
        description="discrete: 11 portal increments; continuous: 7 tip accelerations and the cable "
        "rate (the FASTRL API); rates: 5 portal coordinate rates (first order)",
    )
    pivot_step_deg: Pos = 1.5
    insertion_step: Pos = 0.002
    roll_step_deg: Pos = 4.0
    cable_step_deg: Pos = 4.0
    max_accel: Pos = Field(1.0, description="continuous: tip linear acceleration at |a| = 1 (m/s^2)")
    max_ang_accel: Pos = Field(30.0, description="continuous: tip angular acceleration at |a| = 1 (rad/s^2)")
    max_cable_rate: Pos = Field(2.0, description="continuous and rates: light-cable rate at |a| = 1 (rad/s)")
    max_speed: Pos = Field(0.1, description="continuous: cap on the commanded tip speed (m/s)")
    max_pivot_rate_deg: Pos = Field(30.0, description="rates: pitch and yaw rate at |a| = 1 (deg/s)")
    max_insertion_rate: Pos = Field(0.04, description="rates: insertion rate at |a| = 1 (m/s)")
    max_roll_rate_deg: Pos = Field(80.0, description="rates: roll rate at |a| = 1 (deg/s)")
    max_ang_speed: Pos = Field(2.0, description="continuous: cap on the commanded angular speed (rad/s)")


class TaskSpec(Strict):
    """A whole task: scene, scope, task, episode, actions, observation, reward, train, irl, evaluate, study."""

    name: str = Field(pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = ""
    scene: Scene
    scope: Scope
    instruments: list[Instrument] = Field([], max_length=4, description="probes and graspers besides the scope")
    task: Task
    episode: Episode = Episode()
    actions: Actions = Actions()
    observation: Observation = Observation()
    reward: Reward
    train: Train = Train()
    irl: IRL = IRL()
    evaluate: Evaluate = Evaluate()
    study: Study = Study()

    @model_validator(mode="after")
    def _reachable(self):
        kind = self.train.kind
        if not kind.discrete and self.actions.mode == "discrete":
            _fail(
                "train.algo",
                f"{kind.name} needs continuous actions: set actions.mode: rates (`--set actions.mode=rates`: "
                "portal rates, where the shipped SAC settings learn) or continuous (tip accelerations)",
            )
        if self.train.warm_start is not None and (kind.off_policy or self.irl.enabled):
            _fail("train.warm_start", "the warm start is for PPO on the spec's reward: train.algo: PPO, irl off")
        if self.irl.algorithm == "bc" and kind.off_policy:
            _fail("irl.algorithm", "behavioural cloning trains the PPO policy: set train.algo: PPO")
        image = self.observation.image
        if image is not None and kind.off_policy:
            frame = image.size * image.size * image.channels * image.stack
            gb = 2 * frame * self.train.sac.buffer_size / 1e9  # SB3 keeps each observation and the next
            if gb > MAX_REPLAY_GB:
                _fail(
                    "train.sac.buffer_size",
                    f"{self.train.sac.buffer_size:,} transitions of {frame:,}-byte frames take {gb:.1f} GB of "
                    f"memory, more than {MAX_REPLAY_GB} GB: lower buffer_size or the image's size or stack",
                )
        if self.irl.algorithm in ("gail", "airl") and self.observation.image is not None:
            _fail(
                "irl.algorithm",
                "GAIL and AIRL need the kinematic observation: remove observation.image (pixel policies learn "
                "from the spec's reward, or clone demonstrations: bc)",
            )
        _raise(unobserved_terms(self.irl, self.observation.terms()))
        if self.generator_recorded_starts and (self.instruments or self.task.bodies):
            _fail(
                "irl.generator.recorded_starts",
                "recorded starts replay the scope's poses alone: not for a task with instruments or loose bodies",
            )
        names = [p.name for p in self.scene.portals]
        if self.scope.portal not in names:
            _fail("scope.portal", f"no portal named '{self.scope.portal}' (portals: {', '.join(names)})")
        errors = []
        anatomy = getattr(self.scene, "anatomy", {})
        if self.task.kind == "liver_tour" and self.scene.kind != "abdomen":
            errors.append((("task", "kind"), "liver_tour needs scene.kind: abdomen", self.task.kind))
        errors += episode_term_errors(self)
        for i, lm in enumerate(self.task.landmarks):
            if lm.organ not in anatomy:
                errors.append(
                    (
                        ("task", "landmarks", i, "organ"),
                        f"no organ named '{lm.organ}' (anatomy: {', '.join(anatomy) or 'none'})",
                        lm.organ,
                    )
                )
        one_scope_dome = self.task.kind in DOME_KINDS and not self.instruments and not self.task.bodies
        if self.train.later_subtasks and not one_scope_dome:
            errors.append(
                (
                    ("train", "later_subtasks"),
                    "starts at later subtasks need one scope and a dome task's ordered avatars "
                    f"({', '.join(DOME_KINDS)})",
                    self.train.later_subtasks,
                )
            )
        _raise(errors + instrument_errors(self) + loose_errors(self))
        for i, av in enumerate(self.task.avatars):
            problem = avatar_problem(self, av)
            if problem:
                errors.append((("task", "avatars", i, "at"), problem, list(av.at)))
        for i, lm in enumerate(self.task.landmarks):
            pos, _, _ = landmark_pose(anatomy[lm.organ], portal_point(self))
            problem = reach_problem(self, pos, lm.cue or self.task.cue)
            if problem:
                errors.append((("task", "landmarks", i, "organ"), problem, lm.organ))
        if self.task.line is not None:
            for i, xy in enumerate(self.task.line.points):
                problem = avatar_problem(self, Avatar(surface="plate", at=xy))
                if problem:
                    errors.append((("task", "line", "points", i), problem, list(xy)))
        _raise(errors)
        return self

    @model_validator(mode="before")
    @classmethod
    def _upgrade(cls, data):
        """A spec written in an earlier layout (a run's spec.yaml, a trajectory's or a dataset's) in today's."""
        return upgraded(data)

    @model_validator(mode="wrap")
    @classmethod
    def _resolve_defaults(cls, data, handler):
        """Fill the defaults that depend on the algorithms (null in the spec), so a run's spec.yaml records them."""
        return resolve_defaults(handler(data))

    def learning(self) -> Train:
        """The train settings this run learns with (GAIL and AIRL on PPO: irl.generator's envs and PPO)."""
        return learning_train(self.train, self.irl)

    @property
    def cloned_generator(self) -> bool:
        """Whether GAIL/AIRL's PPO generator starts from the demonstrations' behavioural clone."""
        return starts_cloned(self.train, self.irl)

    @property
    def training_later_subtasks(self) -> float:
        """The share of training episodes that start at a later subtask: forward RL's `train.later_subtasks`, 0
        when learning from demonstrations."""
        return 0.0 if self.irl.algorithm != "none" else self.train.later_subtasks

    @property
    def generator_late_starts(self) -> float:
        """Up to what share of the time limit GAIL/AIRL's PPO generator starts its training episodes late."""
        return late_starts(self.train, self.irl)

    @property
    def generator_recorded_starts(self) -> float:
        """The share of GAIL/AIRL's PPO generator's training episodes that start at a recorded state."""
        return recorded_starts(self.train, self.irl)
