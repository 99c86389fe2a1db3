"""A CNN that reads the scope's portal coordinates off an endoscope frame: the inverse of the task's renderer."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from torch import nn

from ..atomic import atomic_write

INPUT = 64  # frames are averaged down to INPUT x INPUT before the network sees them
VERSION = 4  # of the network and its training: a change here makes every cached estimator stale


def downsample(frames: np.ndarray) -> np.ndarray:
    """(N, H, W, 3) uint8 frames (H, W >= INPUT) as (N, 3, INPUT, INPUT) float16 in [0, 1], each output pixel the
    average of its block of input pixels: the network's inputs (half precision: 45,000 of them in 1.1 GB)."""
    n, h, w, _ = frames.shape
    if h < INPUT or w < INPUT:
        raise ValueError(f"frames of {w}x{h} are smaller than the pose estimator's {INPUT}x{INPUT}")
    if h % INPUT == 0 and w % INPUT == 0:  # whole blocks (the usual 128 x 128): strided adds, 10x faster
        bh, bw = h // INPUT, w // INPUT
        sums = sum(frames[:, i::bh, j::bw].astype(np.uint32) for i in range(bh) for j in range(bw))
        x = sums.astype(np.float32) / (255.0 * bh * bw)
    else:
        rows, cols = (np.arange(INPUT) * h) // INPUT, (np.arange(INPUT) * w) // INPUT
        sums = np.add.reduceat(np.add.reduceat(frames, rows, axis=1, dtype=np.float32), cols, axis=2)
        counts = np.diff(np.append(rows, h))[:, None] * np.diff(np.append(cols, w))[None, :]
        x = sums / (255.0 * counts[None, :, :, None])
    return np.ascontiguousarray(x.transpose(0, 3, 1, 2), dtype=np.float16)


def targets(portal: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """(N, 7): pitch, yaw and insertion scaled to [-1, 1] by the portal's range; sin and cos of roll and cable."""
    lo, hi = ranges[:3, 0], ranges[:3, 1]
    linear = 2 * (portal[:, :3] - lo) / (hi - lo) - 1
    return np.concatenate([linear, np.sin(portal[:, 3:]), np.cos(portal[:, 3:])], axis=1).astype(np.float32)


def coordinates(y: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """The inverse of `targets`: (N, 5) portal coordinates, clipped to the range."""
    lo, hi = ranges[:3, 0], ranges[:3, 1]
    linear = lo + (np.clip(y[:, :3], -1, 1) + 1) * (hi - lo) / 2
    angles = np.arctan2(y[:, 3:5], y[:, 5:7])
    return np.concatenate([linear, angles], axis=1)


class PoseNet(nn.Module):
    """Four stride-2 convolutions and two dense layers: 64 x 64 RGB in, 7 pose targets out."""

    def __init__(self):
        super().__init__()
        chans = [3, 16, 32, 64, 64]
        layers = []
        for a, b in zip(chans[:-1], chans[1:], strict=True):
            layers += [nn.Conv2d(a, b, 3, stride=2, padding=1), nn.ReLU()]
        self.features = nn.Sequential(*layers, nn.Flatten())
        self.head = nn.Sequential(nn.Linear(64 * (INPUT // 16) ** 2, 256), nn.ReLU(), nn.Linear(256, 7))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.features(x))


@dataclass
class PoseEstimator:
    """A trained PoseNet and the task it reads (its portal ranges, frame size and task hash)."""

    net: PoseNet
    ranges: np.ndarray
    size: tuple[int, int]
    task_hash: str
    error: dict  # held-out error of the training run: degrees for angles, mm for insertion

    def portal(self, frames: np.ndarray, batch: int = 512) -> np.ndarray:
        """(T, 5) portal coordinates of (T, H, W, 3) uint8 frames of this task's size."""
        if tuple(frames.shape[2:0:-1]) != self.size:
            raise ValueError(f"frames are {frames.shape[2]}x{frames.shape[1]}, the estimator reads {self.size}")
        return np.concatenate([self.read(downsample(frames[i : i + batch])) for i in range(0, len(frames), batch)])

    def read(self, inputs: np.ndarray, batch: int = 512) -> np.ndarray:
        """(N, 5) portal coordinates of frames already downsampled (`downsample`)."""
        with torch.no_grad():
            out = [
                self.net(torch.from_numpy(inputs[i : i + batch]).float()).numpy() for i in range(0, len(inputs), batch)
            ]
        return coordinates(np.concatenate(out), self.ranges)


def pose_errors(predicted: np.ndarray, truth: np.ndarray) -> dict:
    """Median and 90th percentile absolute errors per coordinate (degrees; insertion in mm)."""
    d = predicted - truth
    d[:, 3:] = (d[:, 3:] + math.pi) % (2 * math.pi) - math.pi
    d = np.abs(d) * np.array([180 / math.pi] * 2 + [1000] + [180 / math.pi] * 2)
    names = ("pitch_deg", "yaw_deg", "insertion_mm", "roll_deg", "cable_deg")
    return {
        n: {"median": float(np.median(d[:, j])), "p90": float(np.percentile(d[:, j], 90))} for j, n in enumerate(names)
    }


def fit(
    inputs: np.ndarray,
    portal: np.ndarray,
    *,
    size: tuple[int, int],
    ranges: np.ndarray,
    task_hash: str,
    seed: int,
    epochs: int,
    held_out: float = 0.1,
    on_epoch=None,
) -> PoseEstimator:
    """Train a PoseNet on labelled frames, downsampled (`downsample`) from frames of `size` (width, height); the last
    `held_out` share is kept for its error; `on_epoch(k, loss)`."""
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    x, y = inputs, targets(portal, ranges)
    cut = int(len(x) * (1 - held_out))
    net = PoseNet()
    optim = torch.optim.AdamW(net.parameters(), lr=2e-3, weight_decay=1e-4)
    steps = epochs * math.ceil(cut / 128)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optim, max_lr=2e-3, total_steps=steps)
    xt, yt = torch.from_numpy(x[:cut]), torch.from_numpy(y[:cut])
    for k in range(epochs):
        order, total = torch.from_numpy(rng.permutation(cut)), 0.0
        for i in range(0, cut, 128):
            idx = order[i : i + 128]
            xb = xt[idx].float() * torch.empty(len(idx), 1, 1, 1).uniform_(0.8, 1.2)  # brightness: lighting, codec
            loss = nn.functional.smooth_l1_loss(net(xb), yt[idx], beta=0.05)
            optim.zero_grad()
            loss.backward()
            optim.step()
            schedule.step()
            total += loss.item() * len(idx)
        if on_epoch is not None:
            on_epoch(k, total / cut)
    net.eval()
    estimator = PoseEstimator(net, np.asarray(ranges, float), tuple(size), task_hash, {})
    if cut < len(x):
        estimator.error = pose_errors(estimator.read(x[cut:]), portal[cut:])
    return estimator


def save(estimator: PoseEstimator, path: Path) -> Path:
    """The estimator as safetensors, its task and error in the file's metadata."""
    from safetensors.torch import save as to_bytes

    meta = {
        "version": str(VERSION),
        "task_hash": estimator.task_hash,
        "size": json.dumps(list(estimator.size)),
        "ranges": json.dumps(estimator.ranges.tolist()),
        "error": json.dumps(estimator.error),
    }
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    blob = to_bytes({k: v.contiguous() for k, v in estimator.net.state_dict().items()}, metadata=meta)
    return atomic_write(Path(path), lambda f: f.write(blob))


def load(path: Path) -> PoseEstimator:
    """An estimator saved by `save` (ValueError if it is of another version or unreadable)."""
    from safetensors import SafetensorError, safe_open
    from safetensors.torch import load_file

    try:
        with safe_open(str(path), framework="pt") as f:
            meta = f.metadata() or {}
        if meta.get("version") != str(VERSION):
            raise ValueError(f"{path}: a pose estimator of version {meta.get('version')}, this fastrl reads {VERSION}")
        net = PoseNet()
        net.load_state_dict(load_file(str(path)))
    except (OSError, RuntimeError, KeyError, json.JSONDecodeError, SafetensorError) as e:
        raise ValueError(f"{path}: not a readable pose estimator ({e})") from None
    net.eval()
    size = tuple(json.loads(meta["size"]))
    return PoseEstimator(net, np.array(json.loads(meta["ranges"])), size, meta["task_hash"], json.loads(meta["error"]))
