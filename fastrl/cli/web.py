"""`fastrl view`: a recording in the local Rerun viewer, or a run's or a sweep's served to a web browser."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from pathlib import Path

import typer
from rich.markup import escape

from . import err, out


def view_web(path: Path, port: int) -> None:
    """Serve the recording(s) under `path`, print the URL (and the SSH tunnel for a remote node), until Ctrl-C."""
    from ..log.web import GRPC_PORT, recordings_of, serve, stop

    try:
        rrds = recordings_of(path)
        served = serve(rrds, web_port=port, grpc_port=GRPC_PORT)
    except (FileNotFoundError, RuntimeError, OSError) as e:
        err.print(str(e), markup=False)
        raise typer.Exit(code=2) from None
    proc, web_port, grpc_port = served.proc, served.web_port, served.grpc_port
    out.print(f"serving {len(rrds)} recording(s) of {escape(str(path))} in Rerun's web viewer; open:", markup=False)
    out.print(served.url, markup=False)
    out.print(
        f"on a remote node, first tunnel both ports: ssh -N -L {web_port}:127.0.0.1:{web_port} "
        f"-L {grpc_port}:127.0.0.1:{grpc_port} NODE  (then open the URL above locally); Ctrl-C stops",
        markup=False,
    )

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, interrupt)  # a terminated `fastrl view --web` takes its viewer along
    try:
        proc.wait()
    except KeyboardInterrupt:
        pass
    finally:
        stop(proc)


def view_local(run_dir: Path) -> None:
    """Open the recording in the local Rerun viewer, or say how to view it where there is no display."""
    rrd = run_dir / "recording.rrd" if run_dir.is_dir() else run_dir
    if not rrd.exists():
        err.print(f"no recording at {rrd}", markup=False)
        raise typer.Exit(code=2)
    viewer = shutil.which("rerun")
    if viewer and (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        from ..log.video import viewer_env

        subprocess.Popen([viewer, str(rrd)], env=viewer_env())
        out.print(f"opening {escape(str(rrd))} in the Rerun viewer")
        return
    out.print(
        f"no display here: copy {escape(str(rrd))} to a machine with a display and run `rerun {rrd.name}`, "
        f"or serve it to a browser with `fastrl view --web {escape(str(run_dir))}`"
    )
