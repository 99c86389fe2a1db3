"""`fastrl view --web`: Rerun's web viewer serves a run on localhost; headless Chromium renders its scene."""

import base64
import io
import json
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request

import numpy as np
import pytest

from fastrl.runner import start_run

from ..conftest import spec_file
from ..runner.test_runner import TINY

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A tiny TraceLines run with its recording."""
    return start_run(
        spec_file("tracelines"),
        [*TINY, "train.timesteps=128"],
        progress=False,
        into=tmp_path_factory.mktemp("web") / "run",
    )


def port_open(port: int) -> bool:
    """Whether something accepts TCP connections on localhost:port."""
    with socket.socket() as s:
        s.settimeout(1)
        return s.connect_ex(("127.0.0.1", port)) == 0


@pytest.fixture
def served(run_dir):
    """`fastrl view --web RUN_DIR` as a user starts it: (URL, web port, gRPC port); stopped with SIGTERM after."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "fastrl.cli", "view", "--web", str(run_dir), "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    lines = [proc.stdout.readline() for _ in range(3)]
    assert lines[0].startswith("serving 1 recording(s)"), "".join(lines) + proc.stdout.read()
    url = lines[1].strip()
    web = int(url.split("/")[2].split(":")[1])
    grpc = int(url.split("%3A")[-1].split("%2F")[0])
    assert f"-L {web}:127.0.0.1:{web}" in lines[2] and f"-L {grpc}:127.0.0.1:{grpc}" in lines[2]  # the SSH tunnel
    yield url, web, grpc
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=20) == 0
    time.sleep(1)
    assert not port_open(web) and not port_open(grpc)  # the viewer went with it


def test_view_web_serves_the_viewer_page_and_the_grpc_endpoint_on_localhost(served):
    url, web, grpc = served
    assert url.startswith(f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy")
    with urllib.request.urlopen(f"http://127.0.0.1:{web}/", timeout=10) as r:
        assert r.status == 200 and "Rerun" in r.read().decode()
    assert port_open(grpc)


def test_view_web_of_a_missing_recording_is_a_one_line_error(tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "fastrl.cli", "view", "--web", str(tmp_path)], capture_output=True, text=True
    )
    assert res.returncode == 2 and "no recording at" in res.stderr and "Traceback" not in res.stderr


def screenshots(url: str, profile, every: float = 3.0, limit: float = 150.0):
    """PNG screenshots of the page in headless Chromium (Chrome DevTools Protocol): at once, then every `every` s."""
    from websockets.sync.client import connect

    flags = [*CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--remote-debugging-port=0"]
    proc = subprocess.Popen(["chromium", *flags, "about:blank"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        port_file = profile / "DevToolsActivePort"
        for _ in range(300):
            if port_file.exists() and port_file.read_text().strip():
                break
            time.sleep(0.1)
        port = port_file.read_text().split()[0]
        pages = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10))
        ws = next(p for p in pages if p["type"] == "page")["webSocketDebuggerUrl"]
        with connect(ws, max_size=None, open_timeout=20) as cdp:
            ids = iter(range(1, 10_000))

            def call(method, **params):
                i = next(ids)
                cdp.send(json.dumps({"id": i, "method": method, "params": params}))
                while (msg := json.loads(cdp.recv(timeout=60))).get("id") != i:
                    pass
                return msg.get("result", {})

            call("Emulation.setDeviceMetricsOverride", width=1280, height=800, deviceScaleFactor=1, mobile=False)
            call("Page.navigate", url=url)
            start = time.monotonic()
            while time.monotonic() - start < limit:
                shot = call("Page.captureScreenshot", format="png")  # empty while the page is still navigating
                if "data" in shot:
                    yield base64.b64decode(shot["data"])
                time.sleep(every)
    finally:
        proc.terminate()
        proc.wait(timeout=20)


def shows_scene(png: bytes) -> bool:
    """Whether the page shows the recorded scene: the dome's shell and the endoscope image are the only warm
    (beige) areas of the viewer, over 1% of the page; the viewer's own panels are neutral greys, white and blue
    (measured here: 2-3% with the scene, 0.06% with the layout loaded but no data yet)."""
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    warm = (rgb[..., 0] - rgb[..., 2] > 20) & (rgb[..., 0] > 100)
    return float(warm.mean()) > 0.01


@pytest.mark.skipif(shutil.which("chromium") is None, reason="chromium is not installed (.ci/run installs it)")
def test_headless_chromium_shows_the_scene(served, tmp_path):
    pytest.importorskip("websockets")
    from PIL import Image

    url, _, _ = served
    shots = []
    for png in screenshots(url, tmp_path / "profile"):
        shots.append(png)
        if shows_scene(png):
            break
    (tmp_path / "view_web.png").write_bytes(shots[-1])
    for blank in (255, 12):  # a blank page, the dark loading screen: the measure tells them from the scene
        buf = io.BytesIO()
        Image.new("RGB", (1280, 800), (blank,) * 3).save(buf, format="PNG")
        assert not shows_scene(buf.getvalue())
    assert shows_scene(shots[-1]), f"no scene after {len(shots)} screenshots: {tmp_path / 'view_web.png'}"
