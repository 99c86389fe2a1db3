"""The recordings `fastrl assess` learns from: every one ranked by a rule, the best K written without their actions,
the rest where the generator starts (fastrl.runner.protocol runs the protocol)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..assess.motion import motion_columns
from ..assess.report import trajectory_files
from ..assess.scoring import Scorer, TrajectoryScores, foreign_problem
from ..data.inverse import to_control_rate
from ..data.trajectory import Trajectory, TrajectoryError
from .score.video import VIDEO_SUFFIXES

BY = {
    "motion": (
        "subtasks completed (more first), then the sum of the ranks by duration and by the motion's likelihood under"
        " the stopwatch's best K (tasks without a motion model: duration)"
    ),
    "time": "subtasks completed (more first), then duration (shorter first)",
    "length": "subtasks completed (more first), then camera path length (shorter first)",
    "heuristic": "the spec's heuristic return (higher first)",
}
# the stopwatch and the motion chose cleaner best 10 than the stopwatch alone on each FAST task's trainee families
# (RESULTS: validity, "The motion beside the stopwatch")
DEFAULT_BY = "motion"


def rank_key(s: TrajectoryScores, by: str) -> tuple:
    """Sort key of a scored trajectory: best first under `by` (ties: the file name)."""
    if by == "heuristic":
        return (-s.scores["heuristic"], s.name)
    return (-s.scores["subtasks"], s.scores["path_length" if by == "length" else "time"], s.name)


def rank_recordings(
    spec, inputs, by: str, top: int | None = None
) -> tuple[list[tuple[TrajectoryScores, Trajectory | None]], list[str]]:
    """Every readable recording of this task on the control grid, scored by replay and sorted best first under
    `by`; the files that cannot be used, as messages naming them (see ranked_by_key). `motion` needs `top`."""
    if by != "motion" or motion_columns(spec) is None:
        return ranked_by_key(spec, inputs, "time" if by == "motion" else by, top)[:2]
    if top is None:
        raise ValueError("ranking by the motion needs the K whose motion is the reference")
    ranked, problems, paths = ranked_by_key(spec, inputs, "time", top)
    return (by_motion(spec, ranked, paths, top) if ranked else ranked), problems


def ranked_by_key(
    spec, inputs, by: str, top: int | None = None
) -> tuple[list[tuple[TrajectoryScores, Trajectory | None]], list[str], dict[int, Path]]:
    """Every readable recording of this task on the control grid, scored by replay and sorted best first; the
    files that cannot be used, as messages naming them. Files are read one at a time and, with `top`, only the best
    `top` keep their trajectory (the others None) and no score keeps its per-sample arrays: memory stays bounded
    however many recordings there are."""
    files = trajectory_files(inputs)
    scorer, hz = Scorer(spec), spec.episode.control_hz
    ranked, unreadable, skipped, paths = [], [], [], {}
    for path in files:
        try:
            traj = Trajectory.load(path)
        except TrajectoryError as e:
            unreadable.append(str(e))
            continue
        try:
            problem = foreign_problem(traj, spec)
            if problem:
                raise TrajectoryError(problem)
            traj = to_control_rate(traj, hz)
            scored = scorer.score(traj, path.stem)
        except (TrajectoryError, ValueError) as e:
            skipped.append(f"{path}: {e}")
            continue
        if top is not None:
            scored.time, scored.tip, scored.values, scored.rewards = np.empty(0), np.empty((0, 3)), None, None
        ranked.append((scored, traj))
        paths[id(scored)] = path
        if top is not None and len(ranked) > 2 * top:  # keep the trajectories of the best `top` so far only
            ranked = _drop_trajectories(ranked, by, top)
    ranked.sort(key=lambda pair: rank_key(pair[0], by))
    return (ranked if top is None else _drop_trajectories(ranked, by, top)), unreadable + skipped, paths


def by_motion(spec, ranked: list, paths: dict[int, Path], top: int) -> list:
    """Recordings ranked by time re-ranked by "motion" (BY): the motion density of the best `top`'s own steps, each
    recording's log-likelihood under it over its replay (its `motion` score), then subtasks and the sum of the two
    ranks; the new best `top` keep their trajectories (read again where dropped), the others none."""
    from scipy.stats import rankdata

    from ..assess.motion import MotionModel, step_motion

    scorer, hz = Scorer(spec), spec.episode.control_hz

    def read(pair: tuple) -> Trajectory:
        """The recording's trajectory, read again where it was dropped."""
        return pair[1] if pair[1] is not None else to_control_rate(Trajectory.load(paths[id(pair[0])]), hz)

    def steps(traj: Trajectory) -> np.ndarray:
        """Its replay's steps (held still to the time limit where it stops early, as scoring replays it)."""
        return step_motion(scorer.replayed(traj)[1], scorer.motion_columns)

    reference = [steps(traj) for _, traj in ranked[:top]]  # replayed once: fitted to, then scored
    model = MotionModel.fit([moves[: len(traj.time)] for moves, (_, traj) in zip(reference, ranked)])
    for k, pair in enumerate(ranked):
        pair[0].scores["motion"] = model.log_likelihood(reference[k] if k < top else steps(read(pair)))
    scores = [s for s, _ in ranked]
    both = rankdata([s.scores["time"] for s in scores]) + rankdata([-s.scores["motion"] for s in scores])
    order = sorted(range(len(ranked)), key=lambda i: (-scores[i].scores["subtasks"], both[i], scores[i].name))
    return [(scores[i], read(ranked[i]) if k < top else None) for k, i in enumerate(order)]


def _drop_trajectories(ranked: list, by: str, top: int) -> list:
    """The list sorted best first, with the trajectories of all but the best `top` dropped."""
    ranked = sorted(ranked, key=lambda pair: rank_key(pair[0], by))
    return ranked[:top] + [(s, None) for s, _ in ranked[top:]]


def write_best(
    chosen: list[tuple[TrajectoryScores, Trajectory]], folder: Path, keep_actions: bool = False
) -> list[Path]:
    """The chosen recordings without their actions (unless `keep_actions`), one file each (names made unique)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for s, traj in chosen:
        path, k = folder / f"{s.name}.npz", 1
        while path.exists():
            k += 1
            path = folder / f"{s.name}-{k}.npz"
        if keep_actions:
            paths.append(traj.save(path))
            continue
        meta = {**traj.meta, "actions": "dropped"} if traj.actions is not None else dict(traj.meta)
        paths.append(
            Trajectory(traj.time, traj.portal, meta, instruments=traj.instruments, bodies=traj.bodies).save(path)
        )
    return paths


def write_demonstrations(run: Path, spec, ranked: list, top: int, inputs: list[Path], keep_actions: bool) -> None:
    """RUN/best: the best `top` recordings; RUN/others: the rest, if the generator starts episodes at their states."""
    write_best(ranked[:top], run / "best", keep_actions)
    generator = spec.irl.generator
    if generator is not None and generator.recorded_starts and len(ranked) > top:
        files = {path.stem: path for path in trajectory_files(inputs)}
        hz = spec.episode.control_hz
        rest = [(s, to_control_rate(Trajectory.load(files[s.name]), hz)) for s, _ in ranked[top:] if s.name in files]
        write_best(rest, run / "others")


def nothing_there(inputs: list[Path]) -> str:
    """Why inputs that hold no recording at all gave nothing to learn from, naming a folder one level down that
    holds some."""
    kinds = (".npz", *VIDEO_SUFFIXES)
    below = [
        f.parent for d in map(Path, inputs) if d.is_dir() for f in sorted(d.glob("*/*")) if f.suffix.lower() in kinds
    ]
    hint = f"; {below[0]} holds some: name that folder" if below else ""
    return f"no recording (.npz or video) in {', '.join(map(str, inputs))}: nothing to learn from{hint}"


def criterion(s: TrajectoryScores) -> dict:
    """The figures a recording was ranked by."""
    return {k: s.scores[k] for k in ("heuristic", "subtasks", "path_length", "time")}
