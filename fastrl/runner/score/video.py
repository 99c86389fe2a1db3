"""Many files at once: trajectories rendered to endoscope videos, videos imported as video-only trajectories."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from rich.progress import Progress

from ...assess.scoring import foreign_problem
from ...data.render_video import write_trajectory_video
from ...data.trajectory import Trajectory, TrajectoryError
from ...data.video import VideoError
from ...data.video_import import endoscope_size, import_video
from ...env.fast_env import FastEnv
from ...spec import SpecError, load_spec
from ...spec.models import TaskSpec

VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov", ".mkv", ".avi", ".webm")


@dataclass(kw_only=True)
class Batch:
    """What a batch wrote (input, output), the inputs it skipped (one line each), frames and seconds taken."""

    written: list[tuple[Path, Path]] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    frames: int = 0
    seconds: float = 0.0


def expand(paths, suffixes: tuple[str, ...]) -> list[Path]:
    """Files as given; folders as their files with these suffixes (any case), sorted."""
    files = []
    for p in map(Path, paths):
        files += sorted(f for f in p.iterdir() if f.suffix.lower() in suffixes) if p.is_dir() else [p]
    return files


def target(src: Path, output: Path | None, suffix: str, single: bool) -> Path:
    """Where one output goes: beside its input, the -o file (one input), or inside the -o folder."""
    if output is None:
        return src.with_suffix(suffix)
    if single and output.suffix.lower() == suffix and not output.is_dir():
        return output
    return output / f"{src.stem}{suffix}"


def _named(path: Path, error: Exception) -> str:
    """One line naming the file and what is wrong with it."""
    text = " ".join(str(error).split())
    return text if text.startswith(str(path)) else f"{path}: {text}"


class _Tasks:
    """One env per task, rendering at the chosen size; the spec is --spec, else the file's bundled spec name."""

    def __init__(self, *, spec: TaskSpec | None, size: tuple[int, int] | None):
        self.spec, self.size, self.envs = spec, size, {}

    def env_for(self, traj: Trajectory) -> FastEnv:
        """The env a trajectory renders in; SpecError or TrajectoryError say why there is none."""
        spec = self.spec
        if spec is None:
            name = traj.meta.get("spec")
            if not name:
                raise TrajectoryError("no --spec given and its meta names no spec")
            spec = self.envs[name].task_spec if name in self.envs else load_spec(name)
        problem = foreign_problem(traj, spec)
        if problem:
            raise TrajectoryError(problem)
        if spec.name not in self.envs:
            w, h = self.size or endoscope_size(spec)
            self.envs[spec.name] = FastEnv(spec, width=w, height=h)
        return self.envs[spec.name]


def render_videos(
    files: list[Path],
    output: Path | None,
    *,
    spec: TaskSpec | None = None,
    size: tuple[int, int] | None = None,
    fps: float | None = None,
    crf: int = 23,
    codec: str = "h264",
    progress: bool = True,
) -> Batch:
    """Each trajectory's endoscope video as an mp4; unreadable or foreign files become messages, the rest render."""
    tasks, batch, t0 = _Tasks(spec=spec, size=size), Batch(), time.perf_counter()
    with Progress(disable=not progress or len(files) < 2) as bar:
        job = bar.add_task("endoscope videos", total=len(files))
        for f in files:
            try:
                traj = Trajectory.load(f)
                env = tasks.env_for(traj)
                out = target(f, output, ".mp4", len(files) == 1)
                scale = size if traj.frames is not None else None
                path, n = write_trajectory_video(env, traj, out, fps=fps, size=scale, crf=crf, codec=codec)
                batch.written.append((f, path))
                batch.frames += n
            except (TrajectoryError, VideoError, SpecError, ValueError) as e:
                batch.errors.append(_named(f, e))
            bar.advance(job)
    batch.seconds = time.perf_counter() - t0
    return batch


def import_videos(
    files: list[Path],
    spec: TaskSpec,
    output: Path | None,
    *,
    meta: dict,
    size: tuple[int, int] | None = None,
    scale: bool = False,
    progress: bool = True,
) -> Batch:
    """Each video as a video-only trajectory (.npz) of `spec`; bad files become messages, the rest are imported."""
    batch, t0 = Batch(), time.perf_counter()
    with Progress(disable=not progress or len(files) < 2) as bar:
        job = bar.add_task("videos", total=len(files))
        for f in files:
            try:
                traj = import_video(f, spec, meta=meta, size=size, scale=scale)
                batch.written.append((f, traj.save(target(f, output, ".npz", len(files) == 1))))
                batch.frames += len(traj.time)
            except (VideoError, TrajectoryError) as e:
                batch.errors.append(_named(f, e))
            bar.advance(job)
    batch.seconds = time.perf_counter() - t0
    return batch
