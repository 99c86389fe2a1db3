"""Offline: replay a recorded attempt (viewer and Rerun), and assist it after the fact (`fastrl assist`)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..agents.expert import ScriptedExpert
from ..assist import Suggester, ValueCue, cue_colour, project_points
from ..data.replay import measured, replay_episode
from ..data.trajectory import Trajectory, TrajectoryError
from ..env.fast_env import FastEnv
from ..irl.networks import has_networks, load_networks
from ..log.attempt import log_attempt
from ..spec import load_spec, spec_hash, task_hash
from ..spec.migrate import in_old_layout
from ..spec.models import TaskSpec


def spec_of_run(run: Path) -> TaskSpec:
    """A run's resolved spec."""
    if not (Path(run) / "spec.yaml").exists():
        raise FileNotFoundError(f"{run} is not a run directory (no spec.yaml)")
    return load_spec(Path(run) / "spec.yaml")


def load_networks_of(run: Path):
    """A run's exported networks (policy and value; reward after inverse RL)."""
    if not has_networks(Path(run) / "networks"):
        raise FileNotFoundError(f"{run} has no exported networks (networks/policy.safetensors)")
    return load_networks(Path(run) / "networks")


def spec_of_trajectory(traj: Trajectory, spec_path: Path | None = None) -> TaskSpec:
    """The spec a trajectory was recorded in: the one it carries, or `spec_path` (checked against its hash)."""
    if spec_path is not None:
        spec = load_spec(spec_path)
    elif "task_spec" in traj.meta:
        carried = traj.meta["task_spec"]
        spec = TaskSpec.model_validate(carried)
        # a spec carried in an earlier layout hashes otherwise once upgraded; its task hash is kept: check that
        key, ours = ("task_hash", task_hash(spec)) if in_old_layout(carried) else ("spec_hash", spec_hash(spec))
        theirs = traj.meta.get(key)
        if theirs is not None and theirs != ours:
            raise TrajectoryError(f"the spec carried in the file does not match its {key} {theirs}")
    else:
        raise TrajectoryError("the trajectory does not carry its spec: give --spec SPEC")
    return spec


def attempt_recording(
    spec: TaskSpec,
    traj: Trajectory,
    out: Path,
    run: Path | None = None,
    every_s: float | None = None,
    feedback_md: str | None = None,
    assistance=None,
    image_every: int = 2,
) -> Path:
    """Replay an attempt into an .rrd with the value cue along the way and, with a run, suggestions every `every_s`."""
    env = FastEnv(spec, width=192, height=192)
    suggester = cue = None
    if assistance is not None:
        suggester, cue = assistance.suggester, assistance.cue
    elif run is not None:
        nets = load_networks_of(run)
        suggester, cue = Suggester(spec, nets.policy), ValueCue(nets)
        expert = ScriptedExpert(FastEnv(spec))
        cue.calibrate(expert.env, {"expert": lambda _o: expert.act()})
    every = max(1, round((every_s or 1.0) * spec.episode.control_hz))
    suggestions, levels, raws = [], [], []

    def on_step(step: int, u: FastEnv) -> None:
        if cue is not None:
            raw = cue.raw(u)
            raws.append(raw)
            levels.append(cue.level(raw))
        if suggester is not None and every_s is not None and step % every == 0:
            sg = suggester.suggest(u)
            cam = u.task.camera
            uvs = []
            for points in (sg.tip, sg.aim):
                points = points[np.isfinite(points).all(axis=1)]
                uv, front = project_points(
                    points, u.data.cam_xpos[cam], u.data.cam_xmat[cam], float(u.model.cam_fovy[cam]), u.width, u.height
                )
                inside = front & (uv[:, 0] >= 0) & (uv[:, 0] <= u.width) & (uv[:, 1] >= 0) & (uv[:, 1] <= u.height)
                uvs.append(uv[inside] if inside.sum() > 1 else None)
            suggestions.append((step, sg, *uvs))

    ep, _ = replay_episode(env, traj, image_every, on_step)
    colours = np.array([cue_colour(x) for x in levels], np.uint8) if levels else None
    recording_id = f"attempt-{traj.meta.get('subject', 'x')}-{traj.meta.get('recorded_at', time.time())}"
    return log_attempt(
        out,
        recording_id,
        env.task,
        ep,
        np.array(raws) if raws else None,
        colours,
        suggestions,
        feedback_md,
        cue.kind if cue is not None else "value",
    )


def replay_in_viewer(spec: TaskSpec, traj: Trajectory, speed: float = 1.0, linger: float = 0.0) -> int:
    """Play the attempt back in the MuJoCo viewer in real time (scaled by `speed`); returns samples shown."""
    import mujoco.viewer

    from .display import check_display, close_viewer

    check_display()
    env = FastEnv(spec)
    env.reset(seed=traj.seed, options={"portal": traj.portal[0], "read_past": measured(traj)})
    handle = mujoco.viewer.launch_passive(env.model, env.data, show_left_ui=False, show_right_ui=False)
    t0, shown = time.monotonic(), 0
    try:
        for t, q in zip(traj.time - traj.time[0], traj.portal):
            if not handle.is_running():
                break
            time.sleep(max(0.0, t / speed - (time.monotonic() - t0)))
            with handle.lock():
                info = env.replay_step(q)[4] if shown else None
            status = f"{traj.meta.get('subject', '?')}  t = {t:.1f} s"
            if info is not None:
                status += f"  subtask {info['subtask']}  {'GREEN' if info['cue']['green'] else 'orange'}"
            handle.set_texts(
                [(mujoco.mjtFontScale.mjFONTSCALE_150, mujoco.mjtGridPos.mjGRID_TOPRIGHT, "replay", status)]
            )
            handle.sync()
            shown += 1
        end = time.monotonic() + linger
        while handle.is_running() and time.monotonic() < end:
            time.sleep(0.1)
    finally:
        close_viewer(handle)
    return shown
