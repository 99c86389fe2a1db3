"""Serve recordings to a browser: Rerun's web viewer and its gRPC server on localhost (`fastrl view --web`)."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

WEB_PORT, GRPC_PORT = 9090, 9876  # Rerun's defaults
HOST = "127.0.0.1"


def recordings_of(path: Path) -> list[Path]:
    """The .rrd files to show for a path: a file itself, a run's recording.rrd, or every run's under a sweep folder."""
    path = Path(path)
    if path.is_file():
        return [path]
    if (path / "recording.rrd").is_file():
        return [path / "recording.rrd"]
    found = sorted(path.glob("*/recording.rrd")) if path.is_dir() else []
    if not found:
        raise FileNotFoundError(f"no recording at {path} (nor in its run directories)")
    return found


def free_port(preferred: int) -> int:
    """`preferred` if nothing listens there on localhost, else a free port the system picks."""
    for port in (preferred, 0):
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            try:
                s.bind((HOST, port))
            except OSError:
                continue
            return s.getsockname()[1]
    raise OSError("no free port on localhost")


def viewer_url(web_port: int, grpc_port: int) -> str:
    """The web viewer's address, told to connect to the gRPC server."""
    return f"http://{HOST}:{web_port}/?url={quote(f'rerun+http://{HOST}:{grpc_port}/proxy', safe='')}"


def rerun_command() -> list[str]:
    """The Rerun CLI of the installed rerun-sdk."""
    exe = shutil.which("rerun")
    return [exe] if exe else [sys.executable, "-m", "rerun"]


@dataclass(frozen=True)
class Served:
    """A running web viewer: its process, the URL to open, and the two ports a tunnel must forward."""

    proc: subprocess.Popen
    url: str
    web_port: int
    grpc_port: int


def serve(rrds: list[Path], web_port: int = WEB_PORT, grpc_port: int = GRPC_PORT, timeout: float = 30.0) -> Served:
    """Start `rerun --web-viewer` on localhost for the recordings; return it once the page answers."""
    web_port, grpc_port = free_port(web_port), free_port(grpc_port)
    cmd = [
        *rerun_command(),
        "--web-viewer",
        "--bind",
        HOST,
        "--port",
        str(grpc_port),
        "--web-viewer-port",
        str(web_port),
        "--hide-welcome-screen",
        *map(str, rrds),
    ]
    env = {**os.environ, "RERUN_ANALYTICS": "0", "CI": os.environ.get("CI", "1")}
    log = tempfile.TemporaryFile()  # a file, not a pipe: a long-running viewer never blocks on its own log
    # its own process group: the `rerun` launcher runs the viewer binary as a child, and stop() ends both
    proc = subprocess.Popen(
        cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True
    )
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            log.seek(0)
            raise RuntimeError(f"the Rerun web viewer stopped: {log.read().decode(errors='replace')[-300:]}")
        try:
            with urllib.request.urlopen(f"http://{HOST}:{web_port}/", timeout=2) as r:
                if r.status == 200:
                    return Served(proc, viewer_url(web_port, grpc_port), web_port, grpc_port)
        except OSError:
            time.sleep(0.2)
    stop(proc)
    raise RuntimeError(f"the Rerun web viewer did not answer on port {web_port} within {timeout:.0f} s")


def stop(proc: subprocess.Popen) -> None:
    """End a viewer started by serve() and its children (its process group)."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
