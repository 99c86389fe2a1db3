"""Endoscope videos in Rerun: each mp4 an AssetVideo, its frames referenced on the `video_time` timeline."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from ..atomic import fsync_dir
from ..cache import cache_dir
from .assessment import skip_pandas_probe
from .stream import saved_stream


def viewer_env(environ: dict[str, str] | None = None) -> dict[str, str]:
    """The environment for Rerun's native viewer: an `ffmpeg` on PATH (imageio-ffmpeg's, linked into the cache),
    without which it cannot decode the H.264 videos of an assessment."""
    env = dict(os.environ if environ is None else environ)
    if shutil.which("ffmpeg", path=env.get("PATH")):
        return env
    import imageio_ffmpeg

    folder = cache_dir() / "bin"
    folder.mkdir(parents=True, exist_ok=True)
    link = folder / "ffmpeg"
    if not link.exists():
        link.unlink(missing_ok=True)  # a dangling link to an earlier install
        try:
            link.symlink_to(imageio_ffmpeg.get_ffmpeg_exe())
        except FileExistsError:  # another process linked it first
            pass
    env["PATH"] = os.pathsep.join([str(folder), *filter(None, [env.get("PATH")])])
    return env


def log_video(rec: rr.RecordingStream, entity: str, mp4: Path) -> int:
    """Log one mp4 as a static AssetVideo with a VideoFrameReference per frame; return the number of frames."""
    asset = rr.AssetVideo(path=str(mp4))
    rec.log(entity, asset, static=True)
    nanos = np.asarray(asset.read_frame_timestamps_nanos(), np.int64)
    rec.send_columns(
        entity,
        indexes=[rr.TimeColumn("video_time", duration=nanos * 1e-9)],
        columns=rr.VideoFrameReference.columns_nanos(nanos),
    )
    return len(nanos)


def write_video_recording(path: Path, videos: list[tuple[str, Path]], app_id: str = "fastrl") -> Path:
    """An .rrd holding each (name, mp4) under `videos/<name>`, one view each; written beside and renamed into place,
    so a failure leaves no half file."""
    skip_pandas_probe()
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    path.parent.mkdir(parents=True, exist_ok=True)
    rec = saved_stream(tmp, app_id=app_id)
    try:
        entities = []
        for name, mp4 in videos:
            entity = f"videos/{name}"
            log_video(rec, entity, mp4)
            entities.append(entity)
        views = [rrb.Spatial2DView(origin=e, name=e.rsplit("/", 1)[-1]) for e in entities]
        rec.send_blueprint(rrb.Blueprint(rrb.Grid(*views), collapse_panels=True))
        rec.flush()
    except BaseException:
        rec.disconnect()
        tmp.unlink(missing_ok=True)
        raise
    rec.disconnect()
    os.replace(tmp, path)
    fsync_dir(path.parent)
    return path
