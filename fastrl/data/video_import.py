"""A video file as a video-only trajectory of a task: frames on the control grid, no portal coordinates."""

from __future__ import annotations

from pathlib import Path

from ..spec import spec_hash, task_hash
from ..spec.limits import MAX_TRAJECTORY_BYTES
from ..spec.models import TaskSpec
from .inverse import to_control_rate
from .trajectory import Trajectory, TrajectoryError
from .video import VideoError, read_video


def endoscope_size(spec: TaskSpec) -> tuple[int, int]:
    """Width and height of the task's endoscope images: those its recordings log (evaluate.image_size)."""
    return tuple(spec.evaluate.image_size)


def import_video(
    path: Path, spec: TaskSpec, *, meta: dict | None = None, size: tuple[int, int] | None = None, scale: bool = False
) -> Trajectory:
    """The video's frames (at `size`, default the task's endoscope size) on the spec's control grid, each tick the
    nearest frame in time; a video of another size is refused unless `scale`. VideoError names the file and fault."""
    path, size = Path(path), tuple(size or endoscope_size(spec))
    video = read_video(path, size, exact_size=not scale)
    hz = spec.episode.control_hz
    if len(video.time) < 2:
        raise VideoError(f"{path}: one frame only; a trajectory needs at least two samples")
    info = {
        "spec": spec.name,
        "spec_hash": spec_hash(spec),
        "task_hash": task_hash(spec),
        "subject": path.stem,
        "source": "human",
        **(meta or {}),
        "imported_from": str(path),
        "video_fps": round(video.fps, 6),
        "video_size": list(video.size),
        "video_frames": len(video.time),
        "video_codec": video.codec,
        **({"video_dropped_frames": video.dropped} if video.dropped else {}),
    }
    try:
        traj = to_control_rate(Trajectory(video.time, None, info, frames=video.frames), hz)
    except (TrajectoryError, ValueError) as e:
        raise VideoError(f"{path}: {e}") from None
    if traj.frames.nbytes > MAX_TRAJECTORY_BYTES:
        raise VideoError(
            f"{path}: {len(traj.time)} frames of {size[0]}x{size[1]} at {hz:g} Hz are "
            f"{traj.frames.nbytes / 2**20:.0f} MiB, more than a trajectory holds ({MAX_TRAJECTORY_BYTES // 2**20} MiB)"
        )
    return traj
