"""Score one trajectory by replaying it: heuristic return, learned reward and value, kinematics."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..data.inverse import to_control_rate
from ..data.replay import replay_arrays
from ..data.trajectory import VIDEO_ONLY, Trajectory, TrajectoryError, recorded_seed
from ..env.fast_env import FastEnv
from ..model.kinematics import Kinematics
from ..spec import task_hash
from ..spec.anatomy import anatomy_vertices
from ..spec.models import TaskSpec
from .kinematic import log_dimensionless_jerk, path_length
from .motion import FILE as MOTION_FILE
from .motion import MotionModel, motion_columns, step_motion
from .tour import tour_metrics

SCORES = ("heuristic", "reward", "value", "potential", "motion", "subtasks", "path_length", "time", "smoothness")
NORMALISED = ("heuristic", "reward", "value", "potential")  # 0 = random policy, 1 = scripted expert
# need a run's networks; potential: shaped AIRL only; motion: a run of fastrl assess (its recordings' motion)
LEARNED = ("reward", "value", "potential", "motion")
HIGHER_IS_BETTER = {
    "heuristic": True,
    "reward": True,
    "value": True,
    "potential": True,
    "motion": True,
    "subtasks": True,
    "path_length": False,
    "time": False,
    "smoothness": True,
    "economy": False,
    "safety": True,
    "contacts": False,
}


@dataclass
class TrajectoryScores:
    """The scores of one replayed trajectory, and the per-sample arrays the pictures need."""

    name: str
    meta: dict
    scores: dict[str, float]  # SCORES -> raw value (None where no learned model)
    time: np.ndarray  # (n,) s, the replayed samples
    tip: np.ndarray  # (n, 3) camera (tip) positions
    values: np.ndarray | None = None  # (n,) learned value of each state
    rewards: np.ndarray | None = None  # (n,) learned reward of each state
    normalised: dict[str, float] = field(default_factory=dict)

    @property
    def subject(self) -> str:
        """The subject named in the metadata, or the file name."""
        return str(self.meta.get("subject") or self.name)

    @property
    def seed(self) -> int:
        """The episode seed the trajectory was recorded with (0 where it gave none)."""
        return recorded_seed(self.meta)

    @property
    def skill(self):
        """The ground-truth skill label, if the file carries one."""
        return self.meta.get("skill")


def foreign_problem(traj: Trajectory, spec: TaskSpec) -> str | None:
    """Why a trajectory belongs to another task than `spec`, or None."""
    theirs = traj.meta.get("task_hash")
    if theirs is not None and theirs != task_hash(spec):
        return f"recorded in another task (task_hash {theirs}, expected {task_hash(spec)})"
    name = traj.meta.get("spec")
    if theirs is None and name is not None and name != spec.name:
        return f"recorded in spec '{name}', not '{spec.name}'"
    return None


class Scorer:
    """Replays trajectories in one compiled task and scores them; learned scores need a run's networks."""

    def __init__(self, spec: TaskSpec, networks=None):
        self.spec = spec
        self.attach(networks)
        self.env = FastEnv(spec)
        self.kin = Kinematics(self.env.task)
        self.anatomy = None
        if spec.scene.kind == "abdomen":
            from scipy.spatial import cKDTree  # here: scipy.spatial costs 0.2 s of every other task's start-up

            self.anatomy = cKDTree(anatomy_vertices(spec.scene))

    def attach(self, networks) -> None:
        """Score with a run's networks from now on (None: heuristic and kinematic scores only), and with the motion
        model beside them, if there is one."""
        self.networks = networks
        self.learned = networks is not None and networks.kind is not None
        self.motion, self.motion_columns = None, motion_columns(self.spec)
        if networks is not None and self.motion_columns and (networks.directory / MOTION_FILE).is_file():
            self.motion = MotionModel.load(networks.directory / MOTION_FILE)

    def tip_path(self, portal: np.ndarray) -> np.ndarray:
        """Camera positions along portal coordinates (forward kinematics on a scratch copy)."""
        return np.array([self.kin.camera(q)[0] for q in portal])

    def score(self, traj: Trajectory, name: str = "") -> TrajectoryScores:
        """Replay and score one trajectory."""
        scored, obs = self.replayed(traj, name)
        self.add_learned(scored, obs)
        return scored

    def replayed(self, traj: Trajectory, name: str = "") -> tuple[TrajectoryScores, np.ndarray]:
        """Replay one trajectory (resampled to the control rate if it is off that grid) and score all but the learned
        scores; also its observations (for add_learned). A trajectory that stops before it succeeds and before the
        time limit is scored as if the trainee then held the scope still until the limit (quitting is not finishing
        fast)."""
        traj = to_control_rate(traj, self.spec.episode.control_hz)
        given = len(traj.time)
        traj = held_to_limit(traj, self.spec, given) or traj  # its first `given` samples are the trajectory's own
        done = replay_arrays(self.env, traj)
        n, tip = len(done.observations), done.tips
        added = held_still(self.spec, given, n, done.success)
        time = traj.time[:n] - traj.time[0]
        scores = {
            "heuristic": float(done.rewards.sum()),
            "subtasks": done.subtasks / max(1, done.subtasks_total),
            "path_length": path_length(tip),
            "time": float(time[-1]),
            "smoothness": log_dimensionless_jerk(tip, time),
            "reward": None,
            "value": None,
            "potential": None,
            "motion": None,
        }
        if self.anatomy is not None:
            scores.update(tour_metrics(tip, done.contacts.tolist(), self.anatomy, self.spec.scene.radius))
        meta = {
            **traj.meta,
            **({"held_still_s": added} if added else {}),
            "success": done.success,
            "subtasks_done": int(done.subtasks),
            "subtasks_total": int(done.subtasks_total),
        }
        return TrajectoryScores(name or str(traj.meta.get("subject", "")), meta, scores, time, tip), done.observations

    def add_learned(self, scored: TrajectoryScores, obs: np.ndarray) -> None:
        """Fill the learned reward, value, potential and motion of a replayed trajectory (nothing without learned
        networks)."""
        density = None if self.motion is None else self.motion.log_density(step_motion(obs, self.motion_columns))
        if self.learned:
            terms = {}
            if density is not None:
                moves = density[1:]
                terms = {
                    "motion_rewards": self.motion.reward(moves),
                    "motion_values": self.motion.value(moves, self.networks.gamma),
                }
            with_learned(scored, learned_scores(self.networks, obs, subtasks_reached(scored.meta), **terms))
        if density is not None:
            scored.scores["motion"] = float(density.sum())

    def load_file(self, path: Path) -> Trajectory:
        """Load and check one file; TrajectoryError or ValueError name the file and the problem."""
        traj = Trajectory.load(path)
        problem = foreign_problem(traj, self.spec) or (VIDEO_ONLY if traj.portal is None else None)
        if problem:
            raise TrajectoryError(f"{path}: {problem}")
        return traj

    def score_file(self, path: Path) -> TrajectoryScores:
        """Load, check and score one file (see load_file)."""
        return self.score(self.load_file(path), Path(path).stem)


def held_to_limit(traj: Trajectory, spec: TaskSpec, replayed: int) -> Trajectory | None:
    """The trajectory's first `replayed` samples, then its last pose held on the control grid up to the time limit
    (None where it already reaches the limit)."""
    hz, total = spec.episode.control_hz, episode_samples(spec)
    if replayed >= total:
        return None
    n, extra = replayed, total - replayed

    def hold(a: np.ndarray | None) -> np.ndarray | None:
        """The first n rows, then the last of them repeated."""
        return None if a is None else np.concatenate([a[:n], np.repeat(a[n - 1 : n], extra, axis=0)])

    time = np.concatenate([traj.time[:n], traj.time[n - 1] + np.arange(1, extra + 1) / hz])
    return Trajectory(time, hold(traj.portal), traj.meta, instruments=hold(traj.instruments), bodies=hold(traj.bodies))


def episode_samples(spec: TaskSpec) -> int:
    """Samples of a whole episode on the control grid, the reset one included."""
    return round(spec.episode.time_limit * spec.episode.control_hz) + 1


def held_still(spec: TaskSpec, given: int, replayed: int, success: bool) -> float:
    """Seconds of stillness added to a trajectory of `given` samples whose held copy replayed `replayed` samples:
    those it held before it succeeded, else the rest of the time limit after its own samples (after the replayed
    ones where the task stopped it earlier)."""
    if success:
        return max(0, replayed - given) / spec.episode.control_hz
    return max(0, episode_samples(spec) - min(given, replayed)) / spec.episode.control_hz


def subtasks_reached(meta: dict) -> int:
    """The subtasks a trajectory reached: those it did and the one it was on when it stopped (all of them once
    done; 1 in a task without subtasks)."""
    return max(1, min(meta["subtasks_done"] + 1, meta["subtasks_total"]))


def learned_scores(
    networks,
    obs: np.ndarray,
    reached: int = 1,
    *,
    motion_rewards: np.ndarray | None = None,
    motion_values: np.ndarray | None = None,
) -> dict:
    """Learned return, value and mean potential of one trajectory's observations, and the value of each state
    ("values") and reward ("rewards"); each trajectory is evaluated as one batch, so its numbers never depend on
    the others. Reward and value count from their ceilings, the best the demonstrations reached, and are summed
    per subtask `reached`: a demonstrated step earns at most zero, every step below costs, a slower trainee never
    scores higher for the time alone, and one who stops early pays the cost of each subtask reached, not of the
    task (RESULTS: validity). Networks saved without a value ceiling keep the mean value. The motion terms of each
    transition (MotionModel.reward) and state (MotionModel.value) are added to the reward and the value."""
    rewards = networks.reward(obs).astype(float) - networks.reward_ceiling
    if motion_rewards is not None:
        rewards = rewards + motion_rewards
    values = networks.value(obs).astype(float)
    ceiling = networks.value_ceiling
    if ceiling is not None:
        values = values - ceiling
    if motion_values is not None:
        values = values + motion_values
    return {
        "reward": float(rewards.sum()) / reached,
        "value": float(values.mean() if ceiling is None else values.sum() / reached),
        "potential": float(networks.potential(obs).mean()) if networks.has_potential else None,
        "values": values,
        "rewards": rewards,
    }


def with_learned(scored: TrajectoryScores, learned: dict) -> None:
    """Fill a trajectory's learned scores and per-state values and rewards from learned_scores' dict."""
    scored.values, scored.rewards = learned["values"], learned["rewards"]
    scored.scores.update({k: v for k, v in learned.items() if k not in ("values", "rewards")})


def normalise(scored: list[TrajectoryScores], references: dict) -> None:
    """Fill each score's `normalised` with (x - random) / (expert - random) for the NORMALISED keys (None where
    the expert does not score above the random policy: such a scale would run backwards)."""
    for s in scored:
        for key in NORMALISED:
            lo, hi, x = references["random"].get(key), references["expert"].get(key), s.scores.get(key)
            if x is None or lo is None or hi is None or hi - lo < 1e-12:  # no gap, or random above expert
                s.normalised[key] = None
            else:
                s.normalised[key] = (x - lo) / (hi - lo)
        s.normalised["subtasks"] = s.scores["subtasks"]
