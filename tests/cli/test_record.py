"""Trainee in the loop: the real MuJoCo viewer under Xvfb driven by xdotool keystrokes, saving, assistance."""

import ctypes
import ctypes.util
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from fastrl.assess.scoring import Scorer
from fastrl.assist import Suggester, project_points
from fastrl.assist.feedback import attempt_feedback, feedback_text
from fastrl.cli import app
from fastrl.data.replay import cue_events, replay
from fastrl.data.trajectory import Trajectory
from fastrl.env import FastEnv
from fastrl.irl.networks import load_networks
from fastrl.spec import load_spec, spec_hash
from fastrl.teleop.keymap import BY_CODE
from fastrl.teleop.session import Session

from ..conftest import spec_file
from ..runner.test_irl_runner import sets
from ..runner.test_runner import only_run, recorded, rrd_verify

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

ROOT = Path(__file__).resolve().parents[2]
# wide tolerances: the cue turns green and subtasks complete while keys move the scope, so there are events
EASY = [
    "episode.time_limit=5",
    "task.cue.centring_deg=40",
    "task.cue.horizon_deg=180",
    "task.cue.distance=[0.001, 0.2]",
    "task.cue.dwell=0.4",
]
UP, ESC = 265, 256

needs_x = pytest.mark.skipif(not (shutil.which("Xvfb") and shutil.which("xdotool")), reason="needs Xvfb and xdotool")


@pytest.fixture(scope="module")
def display():
    """A private Xvfb display for the real viewer window (-noreset: a killed last client must not reset it)."""
    n = next(n for n in range(91, 140) if not Path(f"/tmp/.X{n}-lock").exists())
    proc = subprocess.Popen(
        ["Xvfb", f":{n}", "-screen", "0", "1280x800x24", "-nolisten", "tcp", "-noreset"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    time.sleep(1.0)
    assert proc.poll() is None, "Xvfb did not start"
    yield f":{n}"
    proc.terminate()
    proc.wait(10)


def xenv(display: str) -> dict:
    """Environment of a process that opens the viewer: the display, EGL for offscreen frames, this checkout."""
    return {**os.environ, "DISPLAY": display, "MUJOCO_GL": "egl", "PYTHONPATH": str(ROOT), "CI": "1"}


def start_record(display: str, out: Path, extra=()) -> subprocess.Popen:
    """`fastrl record` in its own process, returned once its window exists."""
    args = [
        sys.executable,
        "-m",
        "fastrl.cli",
        "record",
        str(spec_file("tracelines")),
        "--subject",
        "xdo tester",
        "-o",
        str(out),
        "--linger",
        "0",
        *[a for kv in EASY for a in ("--set", kv)],
        *extra,
    ]
    proc = subprocess.Popen(args, env=xenv(display), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    end = time.monotonic() + 60
    while time.monotonic() < end:
        if proc.poll() is not None:
            pytest.fail(f"fastrl record exited early: {proc.communicate()[1]}")
        found = subprocess.run(
            ["xdotool", "search", "--name", "MuJoCo"],
            env={**os.environ, "DISPLAY": display},
            capture_output=True,
            text=True,
        )
        if found.returncode == 0 and found.stdout.strip():
            return proc
        time.sleep(0.2)
    proc.kill()
    pytest.fail("no viewer window within 60 s")


def xdotool(display: str, *args, timeout: float = 20) -> str:
    """Run xdotool on the test display."""
    res = subprocess.run(
        ["xdotool", *args], env={**os.environ, "DISPLAY": display}, capture_output=True, text=True, timeout=timeout
    )
    assert res.returncode == 0, res.stderr
    return res.stdout


class XClientMessage(ctypes.Structure):
    """Xlib's XClientMessageEvent."""

    _fields_ = [
        ("type", ctypes.c_int),
        ("serial", ctypes.c_ulong),
        ("send_event", ctypes.c_int),
        ("display", ctypes.c_void_p),
        ("window", ctypes.c_ulong),
        ("message_type", ctypes.c_ulong),
        ("format", ctypes.c_int),
        ("l", ctypes.c_long * 5),
    ]


class XEvent(ctypes.Union):
    """Xlib's XEvent (192 bytes)."""

    _fields_ = [("xclient", XClientMessage), ("pad", ctypes.c_long * 24)]


def close_window(display: str, window: int) -> None:
    """What a window manager's close button does: send WM_DELETE_WINDOW (bare Xvfb has no window manager)."""
    x = ctypes.cdll.LoadLibrary(ctypes.util.find_library("X11"))
    x.XOpenDisplay.restype = ctypes.c_void_p
    x.XInternAtom.restype, x.XInternAtom.argtypes = ctypes.c_ulong, [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
    x.XSendEvent.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_long, ctypes.POINTER(XEvent)]
    x.XFlush.argtypes = x.XCloseDisplay.argtypes = [ctypes.c_void_p]
    dpy = x.XOpenDisplay(display.encode())
    ev = XEvent()
    ev.xclient.type, ev.xclient.window, ev.xclient.format = 33, window, 32  # ClientMessage
    ev.xclient.message_type = x.XInternAtom(dpy, b"WM_PROTOCOLS", 0)
    ev.xclient.l[0] = x.XInternAtom(dpy, b"WM_DELETE_WINDOW", 0)
    x.XSendEvent(dpy, window, 0, 0, ctypes.byref(ev))
    x.XFlush(dpy)
    x.XCloseDisplay(dpy)


def only_attempt(out: Path) -> Trajectory:
    """The single attempt saved in out."""
    files = [f for f in out.glob("*.npz") if ".partial" not in f.name]
    assert len(files) == 1, files
    return Trajectory.load(files[0])


@needs_x
def test_keystrokes_to_the_real_window_drive_the_scope_and_the_attempt_replays_to_the_same_cue_events(
    display, tmp_path
):
    proc = start_record(display, tmp_path)
    time.sleep(0.5)
    xdotool(display, "search", "--name", "MuJoCo", "windowfocus", "keydown", "Up", "sleep", "1.0", "keyup", "Up")
    time.sleep(0.5)
    xdotool(display, "search", "--name", "MuJoCo", "windowfocus", "key", "Escape")
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 0, stderr
    traj = only_attempt(tmp_path)
    m = traj.meta
    assert (m["source"], m["subject"], m["complete"], m["end"]) == ("human", "xdo tester", True, "quit")
    spec = load_spec(spec_file("tracelines"), EASY)
    assert m["spec_hash"] == spec_hash(spec)
    assert 1 in set(traj.actions.tolist())  # the Up key became pitch+ actions
    assert traj.portal[:, 0].max() > traj.portal[0, 0] + 0.02  # and the scope pitched (rad)
    assert np.ptp(traj.portal[:, 1]) < 1e-3  # yaw untouched
    assert np.allclose(np.diff(traj.time), 0.05)  # one sample per control step (20 Hz)
    assert 45 < m["realtime"]["period_ms_mean"] < 75  # paced at the control rate (timing: bench, README)
    _, infos, _ = replay(FastEnv(spec), traj)
    assert len(m["events"]) >= 2 and cue_events(infos) == m["events"]
    fb = m["feedback"]  # scored when it ended; the same in the file, beside it, and in its Rerun recording
    # an attempt that stops before it succeeds is scored as held still to the time limit
    timed = traj.time[-1] if infos[-1]["success"] else spec.episode.time_limit
    assert fb["scores"]["time"] == pytest.approx(timed) and fb["worst_moments"]
    saved = next(f for f in tmp_path.glob("*.npz") if ".partial" not in f.name)
    assert saved.with_suffix(".feedback.json").exists() and "/summary" in recorded(saved.with_suffix(".rrd"))[0]
    # and `fastrl replay` plays it back in the viewer and into Rerun
    res = subprocess.run(
        [sys.executable, "-m", "fastrl.cli", "replay", str(saved), "--speed", "4"],
        env=xenv(display),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    assert f"played {len(traj.time)} of {len(traj.time)} samples" in res.stdout
    rrd_verify(saved.with_suffix(".replay.rrd"))


@needs_x
@pytest.mark.parametrize("how", ["SIGINT", "SIGKILL", "close"])
def test_an_interrupted_recording_keeps_what_was_recorded(display, tmp_path, how):
    proc = start_record(display, tmp_path, ["--no-feedback", "--set", "episode.time_limit=60"])
    if how == "SIGINT":  # first pull the scope with the mouse: double-click the shaft, Ctrl + right-drag
        w = xdotool(display, "search", "--name", "MuJoCo").split()[0]
        xdotool(
            display,
            "windowsize",
            w,
            "1280",
            "800",
            "windowmove",
            w,
            "0",
            "0",
            "sleep",
            "1",
            "mousemove",
            "400",
            "411",
            "click",
            "--repeat",
            "2",
            "--delay",
            "80",
            "1",
            "sleep",
            "0.5",
            "keydown",
            "ctrl",
            "mousedown",
            "3",
            "sleep",
            "0.3",
            "mousemove",
            "400",
            "450",
            "sleep",
            "0.3",
            "mousemove",
            "400",
            "500",
            "sleep",
            "1",
            "mouseup",
            "3",
            "keyup",
            "ctrl",
        )
    time.sleep(3.0)
    if how == "close":
        close_window(display, int(xdotool(display, "search", "--name", "MuJoCo").split()[0]))
    else:
        proc.send_signal(getattr(signal, how))
    proc.communicate(timeout=60)
    traj = only_attempt(tmp_path)
    if how == "SIGINT":  # saved in full on the way out
        assert proc.returncode == 0
        assert traj.meta["complete"] and traj.meta["end"] == "interrupted (SIGINT)"
        assert traj.time[-1] >= 2.0
        assert traj.meta["mouse_ticks"] > 0 and np.ptp(traj.portal[:, 2]) > 0.003  # the pull moved the insertion
    elif how == "close":
        assert proc.returncode == 0 and traj.meta["complete"] and traj.meta["end"] == "window closed"
    else:  # no chance to save: the last flush, at most a second old, is on disk
        assert not traj.meta["complete"]
        assert traj.time[-1] >= 1.0


def test_keys_map_to_held_actions_and_commands_through_the_key_callback(tmp_path):
    s = Session(load_spec(spec_file("tracelines")), "cb", tmp_path / "a.npz")
    s.start()
    s.on_key(UP)
    s.on_key(12345)  # not bound: ignored
    t = time.monotonic()
    s.tick(t)
    s.tick(t + 0.05)
    s.tick(t + 0.5)  # the hold (0.15 s) has run out: no-op
    assert s.writer.actions == [1, 1, 0]
    assert BY_CODE[UP].label == "pitch +"
    s.on_key(ESC)
    s.tick()
    assert s.stop == "quit"
    assert s.finish() and Trajectory.load(tmp_path / "a.npz").meta["complete"]


def test_a_point_ahead_projects_to_the_image_centre():
    env = FastEnv(load_spec(spec_file("tracelines")))
    env.reset(seed=0)
    cam = env.task.camera
    pos, mat = env.data.cam_xpos[cam].copy(), env.data.cam_xmat[cam].reshape(3, 3)
    pts = np.array([pos - 0.05 * mat[:, 2], pos - 0.05 * mat[:, 2] + 0.01 * mat[:, 0], pos + 0.05 * mat[:, 2]])
    uv, front = project_points(pts, pos, mat, 80.0, 128, 96)
    assert np.allclose(uv[0], [64, 48]) and uv[1, 0] > 64 and front.tolist() == [True, True, False]


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    """A tiny AIRL run of TraceLines (policy, value and reward networks)."""
    runs = tmp_path_factory.mktemp("runs")
    res = CliRunner().invoke(
        app,
        [
            "irl",
            str(spec_file("tracelines")),
            "--algorithm",
            "airl",
            "--timesteps",
            "256",
            *sets(),
            "--runs",
            str(runs),
            "--no-progress",
        ],
    )
    assert res.exit_code == 0, res.output
    return only_run(runs)


def test_a_suggestion_never_disturbs_the_live_simulation(tiny_run):
    spec = load_spec(tiny_run / "spec.yaml")
    nets = load_networks(tiny_run / "networks")
    live = FastEnv(spec)
    live.reset(seed=3)
    for a in (1, 1, 5, 3):
        live.step(a)
    before = (live.data.qpos.copy(), live.data.qvel.copy(), live.steps, live.done_count, live.observation())
    s = Suggester(spec, nets.policy, horizon_s=2.0).suggest(live)
    after = (live.data.qpos, live.data.qvel, live.steps, live.done_count, live.observation())
    assert all(np.array_equal(a, b) for a, b in zip(before, after))
    assert np.allclose(s.tip[0], live.state.tip_pos) and 2 <= len(s.tip) <= 41
    assert np.ptp(s.tip, axis=0).max() > 0  # the policy moved the scope in the copy


def test_assist_writes_suggestions_and_value_into_rerun_and_feedback_scores_the_attempt(tiny_run, tmp_path):
    demo = sorted((tiny_run / "demos").glob("*.npz"))[0]
    out = tmp_path / "assist.rrd"
    res = CliRunner().invoke(app, ["assist", str(tiny_run), str(demo), "-o", str(out), "--every", "0.5"])
    assert res.exit_code == 0, res.output
    rrd_verify(out)
    entities, timelines = recorded(out)
    assert {
        "/world/attempt/suggestion/tip",
        "/world/attempt/suggestion/view_centre",
        "/metrics/attempt/cue/value",
        "/world/attempt/camera/image/suggestion/view_centre",
    } <= entities and "step" in timelines
    spec = load_spec(tiny_run / "spec.yaml")
    nets = load_networks(tiny_run / "networks")
    fb = attempt_feedback(
        Scorer(spec, nets), Trajectory.load(demo), tmp_path / "refs.json", references=1, policy=nets.policy
    )
    assert fb["normalised"]["heuristic"] is not None and fb["scores"]["reward"] is not None
    assert fb["agent"]["time"] > 0 and "trained agent" in feedback_text(fb)
    assert 1 <= len(fb["worst_moments"]) <= 3 and "largest deviations" in feedback_text(fb)


def test_without_a_display_record_exits_2_with_a_hint(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    res = CliRunner().invoke(app, ["record", str(spec_file("tracelines")), "--subject", "x", "-o", str(tmp_path)])
    assert res.exit_code == 2 and "xvfb-run" in res.output
