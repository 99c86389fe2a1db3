"""`fastrl view --web`: a run's or a sweep's recordings in Rerun's web viewer, served on localhost."""

from __future__ import annotations

import signal
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
