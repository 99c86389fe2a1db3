"""How fast endoscope videos are rendered, encoded, decoded and imported, per stage, at two sizes.

    python bench/video_speed.py                       # 5 scripted-expert TraceLines episodes, 64 and 128 px
    python bench/video_speed.py --episodes 10 --sizes 64 128 256 --spec periscoping

For each size: replay + rendering of the endoscope (frames/s), H.264 encoding (frames/s, bytes per frame), decoding
(frames/s), the whole import of a video-only trajectory (decode, grid, .npz written; frames/s, bytes per frame).
Prints the machine and its load. Times, never asserted; run with MUJOCO_GL=egl on a machine without a display.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from common import machine_line  # noqa: E402

import fastrl  # noqa: E402
from fastrl.data.render_video import rendered_frames  # noqa: E402
from fastrl.data.replay import expert_trajectories  # noqa: E402
from fastrl.data.video import read_video, write_video  # noqa: E402
from fastrl.data.video_import import import_video  # noqa: E402
from fastrl.spec import load_spec  # noqa: E402


def main() -> None:
    """Measure each stage and print one line per size."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--spec", default="tracelines")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 128])
    args = parser.parse_args()
    print(machine_line())
    trajs = expert_trajectories(fastrl.make(args.spec), range(args.episodes))
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes:
            env = fastrl.make(args.spec, width=size, height=size)
            spec = load_spec(args.spec, [f"evaluate.image_size=[{size},{size}]"])
            t, renders = time.perf_counter(), [rendered_frames(env, tr)[1] for tr in trajs]
            render_s, n = time.perf_counter() - t, sum(len(f) for f in renders)
            t, paths = time.perf_counter(), [write_video(Path(tmp) / f"{i}.mp4", f, 20) for i, f in enumerate(renders)]
            encode_s, mp4_bytes = time.perf_counter() - t, sum(p.stat().st_size for p in paths)
            t = time.perf_counter()
            for p in paths:
                read_video(p)
            decode_s = time.perf_counter() - t
            t, saved = time.perf_counter(), [import_video(p, spec).save(p.with_suffix(".npz")) for p in paths]
            import_s, npz_bytes = time.perf_counter() - t, sum(p.stat().st_size for p in saved)
            print(
                f"{size} px, {n} frames: render {n / render_s:.0f}/s, encode {n / encode_s:.0f}/s "
                f"({mp4_bytes / n / 1e3:.2f} kB/frame), decode {n / decode_s:.0f}/s, "
                f"import {n / import_s:.0f}/s ({npz_bytes / n / 1e3:.1f} kB/frame in the .npz)"
            )


if __name__ == "__main__":
    main()
