"""Endoscope video files: read an mp4 (any rate and size) into frames and times, write frames as H.264 mp4.

PyAV (its wheel bundles FFmpeg) does the work; it is imported on first use. Every fault of an input file
raises VideoError with one line naming the file and the fault; writes are atomic (temporary file, rename)."""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..atomic import atomic_write
from ..spec.limits import MAX_TRAJECTORY_BYTES

MAX_DECODED_BYTES = 4 * MAX_TRAJECTORY_BYTES  # frames held while reading one video, after scaling
ASPECT_TOLERANCE = 0.02  # relative difference of width / height still taken as the same view when scaling


class VideoError(ValueError):
    """A video file that cannot be read or written; the message names the file and the fault."""


@dataclass(frozen=True, kw_only=True)
class Video:
    """Decoded frames (T, H, W, 3) uint8 and their times in s from the first frame, with what the file said."""

    frames: np.ndarray
    time: np.ndarray
    fps: float  # the stream's average frame rate
    size: tuple[int, int]  # the file's width, height (frames may be scaled)
    codec: str
    dropped: int = 0  # frames without a later time stamp than the one before, left out


def _av():
    """PyAV, imported on first use (it loads FFmpeg's libraries)."""
    import av

    return av


def _scaling(av):
    """swscale's flags for every conversion here: area averaging, bit-exact, accurate rounding."""
    # the callers add threads=1 (faster at these sizes than swscale's own threads): the same frames, the same pixels
    i = av.video.reformatter.Interpolation
    return i.AREA | i.ACCURATE_RND | i.BITEXACT


def _text(error: Exception) -> str:
    """An FFmpeg error's reason in one line, without its errno and file name."""
    return " ".join(str(getattr(error, "strerror", None) or error).split()) or type(error).__name__


def _fault(path: Path, error: Exception) -> str:
    """One line for an FFmpeg error while opening a file."""
    text = _text(error)
    if "moov atom not found" in text or "Invalid data" in text:
        return f"{path}: not a readable video: corrupt or truncated ({text})"
    return f"{path}: not a readable video ({text})"


def _check_file(path: Path) -> None:
    """Refuse a missing, special (FIFO, device) or empty file before FFmpeg opens it."""
    try:
        st = os.stat(path)
    except OSError as e:
        raise VideoError(f"{path}: cannot read file: {e.strerror or e}") from None
    if not stat.S_ISREG(st.st_mode):
        raise VideoError(f"{path}: not a regular file")
    if st.st_size == 0:
        raise VideoError(f"{path}: empty file (0 bytes), no video in it")


def read_video(path: Path, size: tuple[int, int] | None = None, exact_size: bool = False) -> Video:
    """Every frame of the file's first video stream, as RGB (scaled to `size` (w, h) if given) with its time.

    `exact_size`: refuse a video whose size differs from `size` instead of scaling it. Scaling never changes the
    aspect ratio by more than ASPECT_TOLERANCE: another shape is another view, and is refused."""
    av, path = _av(), Path(path)
    _check_file(path)
    try:
        container = av.open(str(path), mode="r")
    except (av.FFmpegError, OSError, UnicodeDecodeError) as e:
        raise VideoError(_fault(path, e)) from None
    with container:
        if not container.streams.video:
            what = "audio only" if container.streams.audio else "no stream at all: corrupt, or not a video"
            raise VideoError(f"{path}: no video stream ({what})")
        stream = container.streams.video[0]
        w, h = stream.codec_context.width, stream.codec_context.height
        if not (w and h):
            raise VideoError(f"{path}: its video stream declares no frame size")
        _check_size(path, (w, h), size, exact_size)
        out_w, out_h = size or (w, h)
        frames, times, dropped = [], [], 0
        reformatter = av.video.reformatter.VideoReformatter()  # one for the file: a frame's own makes a new context
        scaling = _scaling(av)
        base = stream.time_base or Fraction(1, 1)
        rate = float(stream.average_rate or stream.guessed_rate or 0) or None
        try:
            for i, frame in enumerate(container.decode(stream)):
                t = float(frame.pts * base) if frame.pts is not None else (i / rate if rate else None)
                if t is None:
                    raise VideoError(f"{path}: frame {i} has no time stamp and the stream no frame rate")
                if times and t <= times[-1]:
                    dropped += 1
                    continue
                rgb = reformatter.reformat(
                    frame, format="rgb24", width=out_w, height=out_h, interpolation=scaling, threads=1
                )
                frames.append(rgb.to_ndarray())
                times.append(t)
                if len(frames) * out_w * out_h * 3 > MAX_DECODED_BYTES:
                    raise VideoError(
                        f"{path}: more than {MAX_DECODED_BYTES // 2**20} MiB of {out_w}x{out_h} frames; "
                        "import it at a smaller size"
                    )
        except av.FFmpegError as e:
            raise VideoError(
                f"{path}: corrupt or truncated: decoding failed after {len(frames)} frames ({_text(e)})"
            ) from None
        declared = stream.frames
    if not frames:
        raise VideoError(f"{path}: no decodable frame in its video stream (corrupt or truncated)")
    if declared and len(frames) + dropped < declared:
        raise VideoError(f"{path}: corrupt or truncated: {len(frames) + dropped} of the {declared} frames it declares")
    time = np.asarray(times) - times[0]
    fps = rate if rate else (len(time) - 1) / time[-1] if len(time) > 1 else 0.0
    codec = stream.codec_context.name
    return Video(frames=np.stack(frames), time=time, fps=float(fps), size=(w, h), codec=codec, dropped=dropped)


def _check_size(path: Path, have: tuple[int, int], want: tuple[int, int] | None, exact: bool) -> None:
    """Refuse a video of another size (exact) or another shape (scaled), naming both."""
    if want is None or tuple(want) == tuple(have):
        return
    (w, h), (ww, wh) = have, want
    if exact:
        raise VideoError(f"{path}: the video is {w}x{h}, the task's endoscope images are {ww}x{wh}")
    if abs((w / h) / (ww / wh) - 1.0) > ASPECT_TOLERANCE:
        raise VideoError(
            f"{path}: the video is {w}x{h} (aspect {w / h:.2f}), the task's endoscope images are {ww}x{wh} "
            f"(aspect {ww / wh:.2f}): another view, not scaled"
        )


# codec: (encoder, largest crf, encoder options); one thread each, so the same frames give the same bytes
CODECS = {
    # no B-frames; no macroblock tree: with it, about one encode in two gave other bytes for the same frames in a
    # process that had rendered before (the pose estimator's training frames, every score from video)
    "h264": ("libx264", 51, {"bf": "0", "threads": "1", "mbtree": "0"}),
    "av1": ("libsvtav1", 63, {"preset": "8", "svtav1-params": "lp=1:pred-struct=1"}),  # low delay: no reordering
}


def write_video(
    path: Path,
    frames: np.ndarray,
    fps: float,
    *,
    crf: int = 23,
    size: tuple[int, int] | None = None,
    codec: str = "h264",
) -> Path:
    """Write (T, H, W, 3) uint8 frames as an mp4 (yuv420p; H.264 by x264 or AV1 by SVT-AV1) at `fps`, scaled to
    `size` (w, h) if given; atomically. `crf`: the constant rate factor (x264: 0 lossless luma, 23 its default, 51
    worst; SVT-AV1: up to 63)."""
    av, path = _av(), Path(path)
    frames = np.asarray(frames)
    if frames.dtype != np.uint8 or frames.ndim != 4 or frames.shape[3] != 3 or not len(frames):
        raise VideoError(f"{path}: frames must be (T, H, W, 3) uint8 with T >= 1, got {frames.dtype} {frames.shape}")
    if codec not in CODECS:
        raise VideoError(f"{path}: codec must be one of {', '.join(CODECS)}, got {codec!r}")
    encoder, worst, options = CODECS[codec]
    w, h = size or (frames.shape[2], frames.shape[1])
    if w % 2 or h % 2 or w < 2 or h < 2:
        raise VideoError(f"{path}: yuv420p video needs an even width and height, got {w}x{h}")
    if not (0 < fps <= 1000 and 0 <= crf <= worst):
        raise VideoError(f"{path}: fps must be in (0, 1000] and crf in [0, {worst}], got {fps:g} and {crf}")
    rate = Fraction(fps).limit_denominator(1001)
    os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1 prints its banner to stderr unless told: errors only

    scaling = _scaling(av)

    def encode(f) -> None:
        with av.open(f, mode="w", format="mp4") as container:
            stream = container.add_stream(encoder, rate=rate)
            stream.width, stream.height, stream.pix_fmt = w, h, "yuv420p"
            stream.codec_context.options = {"crf": str(crf), **options}
            stream.codec_context.thread_count = 1
            for i, rgb in enumerate(frames):
                frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
                frame = frame.reformat(width=w, height=h, format="yuv420p", interpolation=scaling, threads=1)
                frame.pts = i
                container.mux(stream.encode(frame))
            container.mux(stream.encode(None))

    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        return atomic_write(path, encode)
    except av.FFmpegError as e:
        raise VideoError(f"{path}: the {codec} encoder refused these frames ({_text(e)})") from None
