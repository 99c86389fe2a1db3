"""One evaluation episode as columns: scope, camera, images, reward-coloured path, cues, scalars."""

from __future__ import annotations

import math

import numpy as np
import rerun as rr

from ..data.episode import EpisodeRecord
from ..model.compiler import CompiledTask
from .instruments import log_instruments
from .shapes import rgba, viridis

GREEN = rgba((0.1, 0.85, 0.2))
ORANGE = rgba((1.0, 0.55, 0.05))
SHAFT = rgba((0.55, 0.57, 0.6))
TIP = rgba((0.95, 0.95, 0.95))
FRUSTUM_DEPTH = 0.015  # m: where the image plane is drawn in 3D


def log_episode(
    rec: rr.RecordingStream,
    ep: EpisodeRecord,
    task: CompiledTask,
    fov_deg: float,
    image_size: tuple[int, int] | None = None,
    world: str = "world/eval/ep_00",
    metrics: str = "metrics/eval/ep_00",
    timesteps: int | None = None,
) -> None:
    """Send the whole episode with send_columns on the `step` and `sim_time` timelines.

    With `timesteps` (the training steps of the policy) the scope, camera, images and cue are also
    placed at that point of the `timesteps` timeline, so the training curves' view shows the
    episode's final state; its scalars stay on `step` (one x for all of them would be a smear).
    """
    steps = np.arange(len(ep.time))
    index = [
        rr.TimeColumn("step", sequence=steps),
        rr.TimeColumn("sim_time", duration=np.asarray(ep.time, float)),
    ]
    scene = index + _trained_at(timesteps, len(steps))
    _log_scope(rec, world, ep, scene, task.spec.scope.diameter)
    _log_camera(rec, world, ep, scene, fov_deg, image_size, timesteps)
    _log_frames(rec, world, ep, timesteps)
    _log_path(rec, world, ep)
    log_instruments(rec, world, ep, scene, task)
    _log_cue(rec, world, ep, scene, task)
    _log_scalars(rec, metrics, ep, index)


def _trained_at(timesteps: int | None, n: int) -> list:
    """A `timesteps` index column holding the policy's training steps on every row (none if unknown)."""
    return [] if timesteps is None else [rr.TimeColumn("timesteps", sequence=np.full(n, int(timesteps)))]


def _log_scope(rec, world: str, ep: EpisodeRecord, index: list, diameter: float) -> None:
    """The shaft as a 2-point strip per step and the tip as a point, style in the columns."""
    n = len(ep.time)
    shaft = np.stack([np.asarray(ep.tip_pos, float), np.asarray(ep.shaft_end, float)], axis=1)
    rec.send_columns(
        f"{world}/shaft",
        indexes=index,
        columns=rr.LineStrips3D.columns(strips=shaft, radii=np.full(n, 0.5 * diameter), colors=np.tile(SHAFT, (n, 1))),
    )
    rec.send_columns(
        f"{world}/tip",
        indexes=index,
        columns=rr.Points3D.columns(
            positions=ep.tip_pos, radii=np.full(n, 0.6 * diameter), colors=np.tile(TIP, (n, 1))
        ),
    )


def _log_camera(rec, world: str, ep: EpisodeRecord, index: list, fov_deg: float, image_size, timesteps=None) -> None:
    """Camera pose per step (MuJoCo wxyz -> xyzw), a static pinhole looking along -Z, the images."""
    # The pinhole takes the images' own size; `image_size` (w, h) serves only when there are none.
    quat = np.asarray(ep.tip_quat, float)[:, [1, 2, 3, 0]]
    rec.send_columns(
        f"{world}/camera",
        indexes=index,
        columns=rr.Transform3D.columns(translation=ep.tip_pos, quaternion=quat),
    )
    keys = sorted(ep.images)
    frames = np.stack([np.asarray(ep.images[k], np.uint8) for k in keys]) if keys else None
    w, h = (frames.shape[2], frames.shape[1]) if frames is not None else (image_size or (128, 128))
    focal = 0.5 * h / math.tan(0.5 * math.radians(fov_deg))  # MuJoCo's fovy is vertical
    image = f"{world}/camera/image"
    rec.log(
        image,
        rr.Pinhole(
            focal_length=focal,
            width=w,
            height=h,
            camera_xyz=rr.ViewCoordinates.RUB,
            image_plane_distance=FRUSTUM_DEPTH,
        ),
        static=True,
    )
    if frames is None:
        return
    _send_images(rec, image, ep, keys, frames, timesteps)


def _log_frames(rec, world: str, ep: EpisodeRecord, timesteps=None) -> None:
    """What a pixel policy saw (its stacked frames side by side) at `world/policy`, on the images' steps."""
    if not ep.frames:
        return
    keys = sorted(ep.frames)
    _send_images(rec, f"{world}/policy", ep, keys, np.stack([ep.frames[k] for k in keys]), timesteps)


def _send_images(rec, path: str, ep: EpisodeRecord, keys: list, frames: np.ndarray, timesteps) -> None:
    """uint8 frames (n, h, w[, c]) as images at `path`, on the steps `keys` of the episode's timelines."""
    h, w = frames.shape[1:3]
    model = {1: "L", 3: "RGB", 4: "RGBA"}[frames.shape[3] if frames.ndim == 4 else 1]
    fmt = rr.components.ImageFormat(width=w, height=h, color_model=model, channel_datatype="U8")
    at = np.asarray(keys)
    index = [
        rr.TimeColumn("step", sequence=at),
        rr.TimeColumn("sim_time", duration=np.asarray(ep.time)[at]),
        *_trained_at(timesteps, len(at)),
    ]
    rec.send_columns(
        path, indexes=index, columns=rr.Image.columns(buffer=frames.reshape(len(keys), -1), format=[fmt] * len(keys))
    )


def _log_path(rec, world: str, ep: EpisodeRecord) -> None:
    """The tip trajectory as 2-point segments coloured by the reward of each step (static)."""
    pos = np.asarray(ep.tip_pos, float)
    if len(pos) < 2:
        return
    segs = np.stack([pos[:-1], pos[1:]], axis=1)
    reward = np.asarray(ep.reward, float)[1:]
    lo, hi = np.nanpercentile(reward, [5, 90])  # a few large bonuses would wash the ramp out
    rec.log(
        f"{world}/trajectory",
        rr.LineStrips3D(segs, radii=0.0008, colors=viridis(reward, lo, hi)),
        static=True,
    )


def _log_cue(rec, world: str, ep: EpisodeRecord, index: list, task: CompiledTask) -> None:
    """The current avatar per step, green while all its cues hold, else orange."""
    pos = task.targets.pos
    if not len(pos):
        return
    k = np.minimum(np.asarray(ep.subtask, int), len(pos) - 1)
    radius = 1.5 * task.targets.size
    lifted = pos + radius * task.targets.fwd  # the whole ball above its surface
    colors = np.where(np.asarray(ep.green, bool)[:, None], GREEN, ORANGE)
    rec.send_columns(
        f"{world}/avatar",
        indexes=index,
        columns=rr.Points3D.columns(positions=lifted[k], colors=colors, radii=np.full(len(k), radius)),
    )


def _log_scalars(rec, metrics: str, ep: EpisodeRecord, index: list) -> None:
    """Reward, every reward feature and the subtask count as time series (legend: leaf names)."""
    series = {"reward": ep.reward, "subtask": ep.subtask}
    series.update({f"features/{name}": v for name, v in ep.features.items()})
    for name, values in series.items():
        rec.send_columns(
            f"{metrics}/{name}",
            indexes=index,
            columns=rr.Scalars.columns(scalars=np.asarray(values, float)),
        )
