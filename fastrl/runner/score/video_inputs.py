"""Videos among a command's inputs become trajectories of estimated portal coordinates, written to a folder."""

from __future__ import annotations

import time
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ...data.trajectory import TrajectoryError
from ...data.video import VideoError
from ...data.video_import import endoscope_size
from ...env.fast_env import FastEnv
from ...spec.models import TaskSpec
from .video import VIDEO_SUFFIXES, Batch, _named

# A pose read off a frame is about 1 degree off in pitch and yaw and 3-5 in the light cable's angle (TraceLines);
# where the scripted expert holds an avatar centred for the dwell's two samples, that is often not centred at all.
VIDEO_CENTRING = 2.0


def video_files(inputs: list[Path]) -> tuple[list[Path], list[Path]]:
    """(videos, the rest): video files named, or inside named folders that hold no .npz trajectory (a folder with
    both is a folder of trajectories), and every other input as given."""
    videos, rest = [], []
    for p in map(Path, inputs):
        if p.is_dir() and not any(p.glob("*.npz")):
            found = sorted(f for f in p.iterdir() if f.suffix.lower() in VIDEO_SUFFIXES)
            videos += found
            rest += [] if found else [p]
        elif p.suffix.lower() in VIDEO_SUFFIXES:
            videos.append(p)
        else:
            rest.append(p)
    return videos, rest


def video_overrides(spec: TaskSpec) -> list[str]:
    """The spec changes under which videos are replayed: the centring tolerance times VIDEO_CENTRING."""
    return [f"task.cue.centring_deg={spec.task.cue.centring_deg * VIDEO_CENTRING:g}"]


def _bar(progress: bool, console: Console) -> Progress:
    """A progress bar with a description that changes."""
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    return Progress(*columns, console=console, disable=not progress)


def videos_as_trajectories(
    inputs: list[Path],
    spec: TaskSpec,
    folder: Path,
    *,
    recorded: TaskSpec | None = None,
    places=(),
    console: Console,
    progress: bool = True,
) -> tuple[list[Path], Batch, Path | None]:
    """The inputs with their videos replaced by `folder`, where each video's estimated trajectory is written; the
    batch (written pairs, one line per skipped video) and the estimator's file (None without videos). `recorded`:
    the spec the videos were recorded under, where it differs from `spec` (a new estimator learns its frames)."""
    videos, rest = video_files(inputs)
    batch = Batch()
    if not videos:
        return list(inputs), batch, None
    from ...data.video_poses import estimator_for, video_trajectory  # here: scoring trajectories needs no torch

    w, h = endoscope_size(spec)
    # renders as the videos were: the cue's tolerances colour the avatars, and an estimator that learned from frames
    # of a wider cue than the videos' read their poses worse (RESULTS: scores from the endoscope video)
    env = FastEnv(recorded or spec, width=w, height=h)
    with _bar(progress, console) as bar:
        job = bar.add_task("pose estimator", total=None)

        def show(done, total, what):
            bar.update(job, description=what, completed=done, total=total)

        estimator, source = estimator_for(env, places=list(places), progress=show)
        console.print(f"pose estimator: {source} (held-out error {_error_text(estimator.error)})", markup=False)
        t0 = time.perf_counter()
        bar.update(job, description="videos to poses", completed=0, total=len(videos))
        folder.mkdir(parents=True, exist_ok=True)
        for f in videos:
            try:
                traj = video_trajectory(f, spec, estimator, source)
                batch.written.append((f, traj.save(folder / f"{f.stem}.npz")))
                batch.frames += len(traj.time)
            except (VideoError, TrajectoryError) as e:
                batch.errors.append(_named(f, e))
            bar.advance(job)
    batch.seconds = time.perf_counter() - t0
    return [*rest, folder], batch, source


def _error_text(error: dict) -> str:
    """Median errors in one line."""
    if not error:
        return "not measured"
    unit = {"insertion_mm": "mm"}
    return ", ".join(f"{k.split('_')[0]} {v['median']:.1f} {unit.get(k, 'deg')}" for k, v in error.items())
