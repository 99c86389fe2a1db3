"""Endoscope videos: `fastrl render-video` (trajectories to mp4) and `fastrl import-video` (mp4 to trajectories)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from . import SetOpt, app, err, load_or_exit, out
from .poses import _number_or_text

SizeOpt = Annotated[
    str | None, typer.Option(metavar="WxH", help="frame size (default: the spec's evaluate.image_size)")
]
ProgressOpt = Annotated[bool, typer.Option(help="show the progress bar")]


def parse_size(text: str | None) -> tuple[int, int] | None:
    """'64x48' as (64, 48); exit 2 with a message if it is not two positive even whole numbers."""
    if text is None:
        return None
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        w = h = 0
    if w < 2 or h < 2 or w % 2 or h % 2 or w > 4096 or h > 4096:
        err.print(f"--size {text}: give WIDTHxHEIGHT, even numbers from 2 to 4096 (H.264 yuv420p)", markup=False)
        raise typer.Exit(code=2)
    return w, h


def _check_output(output: Path | None, files: list[Path], suffix: str) -> None:
    """Exit 2 if several inputs are to go into one -o file."""
    if output is not None and len(files) > 1 and output.suffix.lower() == suffix and not output.is_dir():
        err.print(f"-o {output}: {len(files)} inputs go into a folder, not one {suffix} file", markup=False)
        raise typer.Exit(code=2)


def _finish(batch, verb: str, unit: str) -> None:
    """Print each skipped file in one line and the totals; exit 2 if any was skipped."""
    for line in batch.errors:
        err.print(f"skipped {line}", markup=False, style="yellow")
    rate = batch.frames / batch.seconds if batch.seconds > 0 else 0.0
    out.print(
        f"{verb} {len(batch.written)} {unit} ({batch.frames} frames, {rate:.0f} frames/s); {len(batch.errors)} skipped"
    )
    if len(batch.written) == 1:
        out.print(f"  {escape(str(batch.written[0][1]))}")
    if batch.errors or not batch.written:
        raise typer.Exit(code=2)


@app.command(name="render-video")
def render_video(
    inputs: Annotated[
        list[Path], typer.Argument(metavar="TRAJ", help="trajectory .npz files or folders", show_default=False)
    ],
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="FILE.mp4 for one trajectory, else a folder (default: beside)")
    ] = None,
    spec: Annotated[
        Path | None, typer.Option(metavar="SPEC", help="the task (default: the bundled spec each file names)")
    ] = None,
    size: SizeOpt = None,
    fps: Annotated[float | None, typer.Option(help="frames per second (default: the control rate)")] = None,
    crf: Annotated[int, typer.Option(help="quality: 0 best, 23 default; worst 51 (h264), 63 (av1)")] = 23,
    codec: Annotated[
        str, typer.Option(help="h264, or av1 (Rerun's native viewer decodes it without an ffmpeg executable)")
    ] = "h264",
    rrd: Annotated[Path | None, typer.Option(help="also write a Rerun recording of the videos")] = None,
    set_: SetOpt = None,
    progress: ProgressOpt = True,
) -> None:
    """Write the endoscope video (H.264 mp4) of trajectories: their frames, or their replay rendered."""
    from ..data.video import CODECS
    from ..runner.score.video import expand, render_videos

    files = expand(inputs, (".npz",))
    _check_output(output, files, ".mp4")
    if codec not in CODECS:
        err.print(f"--codec must be one of {', '.join(CODECS)}, got {codec!r}", markup=False)
        raise typer.Exit(code=2)
    if fps is not None and not 0 < fps <= 1000 or not 0 <= crf <= CODECS[codec][1]:
        err.print(f"--fps must be in (0, 1000] and --crf in [0, {CODECS[codec][1]}] for {codec}", markup=False)
        raise typer.Exit(code=2)
    if set_ and spec is None:
        err.print("--set changes a spec: give it with --spec", markup=False)
        raise typer.Exit(code=2)
    task = load_or_exit(spec, set_).spec if spec is not None else None
    sized = parse_size(size)
    batch = render_videos(files, output, spec=task, size=sized, fps=fps, crf=crf, codec=codec, progress=progress)
    if rrd is not None and batch.written:
        from ..log.video import write_video_recording

        try:
            write_video_recording(rrd, [(mp4.stem, mp4) for _, mp4 in batch.written])
        except (OSError, RuntimeError, ValueError) as e:
            err.print(f"cannot write {rrd}: {' '.join(str(e).split())}", markup=False)
            raise typer.Exit(code=1) from None
        out.print(f"  recording: {escape(str(rrd))}")
    _finish(batch, "wrote", "videos")


@app.command(name="import-video")
def import_video_(
    inputs: Annotated[
        list[Path], typer.Argument(metavar="VIDEO", help="video files (.mp4, ...) or folders", show_default=False)
    ],
    spec: Annotated[Path, typer.Option(metavar="SPEC", help="the task the videos show")],
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="FILE.npz for one video, else a folder (default: beside)")
    ] = None,
    size: SizeOpt = None,
    scale: Annotated[bool, typer.Option(help="scale videos of another size (same aspect) instead of skipping")] = False,
    subject: Annotated[str | None, typer.Option(help="who held the scope (default: the file name)")] = None,
    skill: Annotated[str | None, typer.Option(help="skill label, if known (a number is ranked)")] = None,
    source: Annotated[str, typer.Option(help="agent, expert, human or synthetic")] = "human",
    seed: Annotated[int | None, typer.Option(help="episode seed of the session (avatar jitter)")] = None,
    set_: SetOpt = None,
    progress: ProgressOpt = True,
) -> None:
    """Read videos into video-only trajectories: frames on the control grid, no portal coordinates."""
    from ..data.trajectory import SOURCES
    from ..runner.score.video import VIDEO_SUFFIXES, expand, import_videos

    files = expand(inputs, VIDEO_SUFFIXES)
    _check_output(output, files, ".npz")
    if source not in SOURCES:
        err.print(f"--source must be one of {', '.join(SOURCES)}, got {source!r}", markup=False)
        raise typer.Exit(code=2)
    task = load_or_exit(spec, set_)
    meta = {"source": source}
    given = (("subject", subject), ("skill", _number_or_text(skill)), ("seed", seed))
    meta.update({k: v for k, v in given if v is not None})
    batch = import_videos(files, task.spec, output, meta=meta, size=parse_size(size), scale=scale, progress=progress)
    _finish(batch, "imported", "videos")
