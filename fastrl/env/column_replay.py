"""Replay a recording over all its samples at once (scoring's replay): the kinematics in one loop of MuJoCo calls,
the cue machine in a loop over precomputed checks, the terms as arrays (`terms.columns`). It gives what replaying
step by step (`FastEnv.replay_step`) gives, for the scope-only tasks whose terms all have array forms; the rest
replay step by step (`can_replay_columns`)."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from ..terms.columns import (
    FEATURE_COLUMNS,
    OBSERVATION_COLUMNS,
    Columns,
    acos,
    atan2,
    cue_potential,
    dot,
    mat_quat,
    norm,
)
from .dome_task import DomeTask
from .sensing import avatar_ray_points
from .tour_task import TourTask

TERMINATIONS = {"subtasks_done"}  # the termination terms this replay knows


@dataclass
class Replayed:
    """What a replay of one recording gives scoring."""

    observations: np.ndarray  # (n, obs) float32, as the env observes
    rewards: np.ndarray  # (n,) the spec's reward, 0 at the reset sample
    tips: np.ndarray  # (n, 3) camera positions
    contacts: np.ndarray  # (n,) contacts at each sample
    subtasks: int  # subtasks completed
    subtasks_total: int

    @property
    def success(self) -> bool:
        """Whether every subtask was completed."""
        return self.subtasks >= self.subtasks_total


def can_replay_columns(env) -> bool:
    """Whether this env's task replays by columns: the scope alone, state observations, known terms."""
    u = env.unwrapped
    spec = u.task_spec
    return (
        type(u.family) in (DomeTask, TourTask)
        and u.frames is None
        and u.stack == 1
        and set(spec.observation.terms()) <= set(OBSERVATION_COLUMNS)
        and set(u.feature_names) <= set(FEATURE_COLUMNS)
        and set(spec.episode.terminations) <= TERMINATIONS
    )


def replay_columns(env, portal: np.ndarray, seed: int, read_past: bool = False) -> Replayed:
    """Replay portal coordinates (n, 5) from the reset with `seed`, as episode_steps would, until the task ends
    (`read_past`: measured poses, read with Task.read_past)."""
    u = env.unwrapped
    q = np.asarray(portal, float)
    bad = np.flatnonzero(~np.isfinite(q).all(axis=1))
    if len(bad):
        raise ValueError(f"portal coordinates must be 5 finite numbers, got {q[bad[0]]!r}")
    u.reset(seed=seed, options={"portal": q[0]})
    ranges = u.task.ranges
    q = np.minimum(np.maximum(q, ranges[:, 0]), ranges[:, 1])
    still = np.concatenate([[False], (q[1:] == q[:-1]).all(axis=1)]).tolist()  # the same pose: the same kinematics
    pos, mat, contacts = _kinematics(u, q, still)
    k = 1.0 / u.state.dt
    vel, accel, rate, qvel = (np.zeros(s) for s in (pos.shape, pos.shape, (len(q), 4), q.shape))
    vel[1:] = (pos[1:] - pos[:-1]) * k
    accel[1:] = (vel[1:] - vel[:-1]) * k
    quat = mat_quat(mat)
    before = quat[:-1].copy()
    a, b = quat[1:], before
    before[a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2] + a[:, 3] * b[:, 3] < 0] *= -1.0
    rate[1:] = (quat[1:] - before) * k
    qvel[1:] = (q[1:] - q[:-1]) * k
    cam = {"fwd": -mat[:, [2, 5, 8]], "up": mat[:, [1, 4, 7]], "right": mat[:, [0, 3, 6]]}
    errors = _target_errors(u, pos, cam)
    cue = _cue_machine(u, errors["green"], read_past)
    end = cue["end"]
    sensor = u.family.sensor
    line = sensor.line_deviations(pos, cam["fwd"]) if sensor.line is not None else np.zeros(len(q))
    if sensor.rays:
        rays = _ray_fractions(u, q, pos, cam["fwd"], still, cue["feature_target"], end)
    samples = {
        "tip_pos": pos, "cam_pos": pos, "tip_quat": quat, "tip_vel": vel, "tip_quat_rate": rate, "tip_accel": accel,
        "tip_speed": norm(vel), "cam_fwd": cam["fwd"], "cam_up": cam["up"], "cam_right": cam["right"],
        "portal": q, "portal_vel": qvel, "contacts": contacts, "line_deviation": line,
        "ray_fraction": rays if sensor.rays else np.zeros(len(q)),
    }  # fmt: skip
    steps = np.arange(1, end)
    features = _columns(u, samples, errors, steps, cue["feature_target"][steps], cue["feature_dwell"][steps])
    features.dwell_gain, features.completed = cue["gain"][steps], cue["completed"][steps]
    rewards = np.zeros(end)
    if end > 1:
        reward = 0
        for name, w in zip(u.feature_names, u.weights):
            reward = reward + w * FEATURE_COLUMNS[name](features, **u.task_spec.reward.features[name].params)
        rewards[1:] = reward
    every = np.arange(end)
    seen = _columns(u, samples, errors, every, cue["target"][every], cue["dwell"][every])
    obs = np.concatenate(
        [np.asarray(OBSERVATION_COLUMNS[n](seen)).reshape(end, -1) for n in u.task_spec.observation.terms()], axis=1
    )
    return Replayed(obs.astype(np.float32), rewards, pos[:end], contacts[:end], cue["done"], len(u.family.t_pos))


def _kinematics(u, q: np.ndarray, still: list[bool]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera positions (n, 3), rotations (n, 9) and contact counts (n,) at each sample; the first is the reset's.
    A sample `still` at the previous one's pose takes its kinematics."""
    m, d, ct = u.model, u.data, u.task
    n, cam = len(q), ct.camera
    pos, mat, contacts = np.empty((n, 3)), np.empty((n, 9)), np.empty(n, np.int64)
    xpos, xmat, qpos = d.cam_xpos[cam], d.cam_xmat[cam], d.qpos
    joints, lens = u.family.sensor.qslice, ct.lens_qadr
    pos[0], mat[0], contacts[0] = xpos, xmat, d.ncon
    lens_q = -q[:, 4]
    for t in range(1, n):
        if still[t]:
            pos[t], mat[t], contacts[t] = pos[t - 1], mat[t - 1], contacts[t - 1]
            continue
        qpos[joints] = q[t]
        qpos[lens] = lens_q[t]
        mujoco.mj_fwdPosition(m, d)
        pos[t], mat[t], contacts[t] = xpos, xmat, d.ncon
    u.family.positions_only = True  # as after a replayed step: a later env.step completes the forward pass first
    return pos, mat, contacts


def _ray_fractions(u, q, pos, fwd, still: list[bool], target: np.ndarray, end: int) -> np.ndarray:
    """The share of its target's ray points each sample sees (Sensor.ray_fraction), the scene placed again at each
    pose: the rays need it."""
    fam, m, d, sensor = u.family, u.model, u.data, u.family.sensor
    size, qpos, joints, lens = u.task.targets.size, d.qpos, sensor.qslice, u.task.lens_qadr
    points = [avatar_ray_points(size, fam.t_pos[k], fam.t_fwd[k], fam.t_up[k]) for k in range(len(fam.t_pos))]
    out, target = np.zeros(len(q)), target.tolist()
    for t in range(1, end):
        if t > 1 and still[t] and target[t] == target[t - 1]:
            out[t] = out[t - 1]
            continue
        qpos[joints] = q[t]
        qpos[lens] = -q[t, 4]
        mujoco.mj_kinematics(m, d)  # rays read the geoms' poses only
        out[t] = sensor.ray_fraction(m, d, points[target[t]], tuple(pos[t].tolist()), tuple(fwd[t].tolist()))
    return out


def _target_errors(u, pos: np.ndarray, cam: dict) -> dict:
    """Distance, centring, horizon, potential and the cue's green of every sample against every target (N, n)."""
    fam, t = u.family, u.task.targets
    n, count = len(pos), len(fam.t_pos)
    out = {k: np.empty((count, n)) for k in ("distance", "centring", "horizon", "potential")}
    for j in range(count):
        d = fam.t_pos[j] - pos
        dist = norm(d)
        out["distance"][j] = dist
        out["centring"][j] = acos(np.clip(dot(d, cam["fwd"]) / np.maximum(dist, 1e-9), -1.0, 1.0))
        up = fam.t_up[j][None, :]
        out["horizon"][j] = np.abs(atan2(dot(up, cam["right"]), dot(up, cam["up"])))
        limits = Columns(
            centring=out["centring"][j], horizon=out["horizon"][j], distance=dist, dist_lo=float(t.dist[j, 0]),
            dist_hi=float(t.dist[j, 1]), tol_centring=float(t.centring[j]), tol_horizon=float(t.horizon[j]),
        )  # fmt: skip
        out["potential"][j] = cue_potential(limits)
    lo, hi = t.dist[:, :1], t.dist[:, 1:]
    out["green"] = (
        (out["centring"] <= t.centring[:, None])
        & (out["horizon"] <= t.horizon[:, None])
        & (lo <= out["distance"])
        & (out["distance"] <= hi)
    )
    return out


def _cue_machine(u, green: np.ndarray, read_past: bool) -> dict:
    """The cue's dwell, completions and current target at each sample (Task.after_step, read_past and
    next_subtask in turn): the target the reward sees and the one the observation sees after a completion moved it
    on. With `read_past`, the next avatar's dwell held while one is current completes both (Task.read_past)."""
    fam = u.family
    n, count, dt = green.shape[1], green.shape[0], fam.dt
    dwells = fam.compiled.targets.dwell.tolist()
    rows = green.tolist()
    stops = bool(u.task_spec.episode.terminations)
    k = done = 0
    elapsed = ahead = dwell = best = 0.0
    feature_target, feature_dwell, gain, completed = [0], [0.0], [0.0], [False]
    target, seen_dwell = [0], [0.0]
    end = n
    for t in range(1, n):
        g = rows[k][t]
        elapsed = elapsed + dt if g else 0.0
        need = dwells[k]
        dwell = 1.0 if need <= 0 else min(1.0, elapsed / need)
        gain.append(max(0.0, dwell - best))
        best = max(best, dwell)
        finished = g and elapsed >= need - 1e-9
        seen = read_past and k + 1 < count and rows[k + 1][t]
        ahead = ahead + dt if seen else 0.0
        passed = seen and not finished and ahead >= dwells[k + 1] - 1e-9
        feature_target.append(k)
        feature_dwell.append(dwell)
        completed.append(finished or passed)
        if finished or passed:
            done += 2 if passed else 1
            elapsed = ahead = 0.0
            if done < count:
                k, dwell, best = done, 0.0, 0.0
        target.append(k)
        seen_dwell.append(dwell)
        if stops and done >= count:
            end = t + 1
            break
    arrays = {
        "feature_target": feature_target, "feature_dwell": feature_dwell, "gain": gain, "completed": completed,
        "target": target, "dwell": seen_dwell,
    }  # fmt: skip
    return {k: np.array(v) for k, v in arrays.items()} | {"done": done, "end": end}


def _columns(u, samples: dict, errors: dict, steps: np.ndarray, target: np.ndarray, dwell: np.ndarray) -> Columns:
    """The state's columns at `steps`, each against its `target` (the subtask index), with the dwell fill given."""
    fam, t, s = u.family, u.task.targets, u.state
    last = len(fam.t_pos) - 1
    return Columns(
        **{name: column[steps] for name, column in samples.items()},
        time=steps * s.dt,
        time_limit=s.time_limit,
        dt=s.dt,
        gamma=s.gamma,
        fov=s.fov,
        portal_lo=s.portal_lo,
        portal_hi=s.portal_hi,
        target_pos=fam.t_pos[target],
        target_quat=fam.t_quat[target],
        target_fwd=fam.t_fwd[target],
        target_up=fam.t_up[target],
        centring=errors["centring"][target, steps],
        horizon=errors["horizon"][target, steps],
        distance=errors["distance"][target, steps],
        potential=errors["potential"][target, steps],
        prev_potential=errors["potential"][target, np.maximum(steps - 1, 0)],
        dist_lo=t.dist[target, 0],
        dist_hi=t.dist[target, 1],
        tol_centring=t.centring[target],
        tol_horizon=t.horizon[target],
        dwell_time=t.dwell[target],
        dwell=dwell,
        subtask=target,
        subtasks_total=last + 1,
        goals=fam.t_pos[np.minimum(target + 1, last)],
    )
