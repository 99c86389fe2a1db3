"""Resource limits on every input fastrl reads (specs, trajectories, pose CSVs), in one place."""

from __future__ import annotations

import os
import stat
from typing import BinaryIO

# Spec files (YAML)
MAX_SPEC_BYTES = 256 * 1024  # a shipped spec is about 6 KB
MAX_YAML_DEPTH = 32  # nesting of lists and mappings (a shipped spec nests 6 deep)
MAX_YAML_ITEMS = 1000  # entries of one list or mapping
MAX_YAML_NODES = 100_000  # values after expanding every alias (*name): stops "billion laughs"
MAX_INT = 2**63 - 1  # integers beyond this do not fit numpy, torch or MuJoCo
MAX_LINE_POINTS = 100  # task.line.points (a shipped line has 4)
MAX_SUBTASKS = 500  # avatars, landmarks, or avatars placed along the line
MAX_REPLAY_GB = 4  # memory of SAC's replay buffer of image observations
MAX_EPISODE_STEPS = 1_000_000  # episode.time_limit * episode.control_hz
MAX_SECONDS = 86_400  # episode.time_limit, and the time span of a trajectory or pose session
MIN_TIME_STEP = 1e-6  # s between trajectory samples
MAX_MESH_BYTES = 64 * 1024 * 1024  # an organ's OBJ or STL file

# Trajectory files (.npz)
MAX_TRAJECTORY_BYTES = 256 * 1024 * 1024  # on disk, and the arrays after decompression
MAX_TRAJECTORY_SAMPLES = MAX_EPISODE_STEPS + 1  # rows of time and portal
MAX_META_CHARS = 1_000_000  # the metadata JSON string
MAX_META_DEPTH = 32  # nesting of the metadata JSON
MAX_SEED = 2**63 - 1  # meta.seed
RANGE_TOLERANCE = (0.05, 0.05, 0.005, 0.05, 0.05)  # rad, rad, m, rad, rad past a joint limit still replayed

# Pose CSVs
MAX_POSE_BYTES = 256 * 1024 * 1024
MAX_POSE_ROWS = MAX_TRAJECTORY_SAMPLES  # rows read, and samples after resampling
MAX_POSE_SECONDS = MAX_SECONDS  # time span of the accepted samples

LIMITS = [
    ("spec file size", f"{MAX_SPEC_BYTES // 1024} KiB", "a larger file is refused before it is parsed"),
    ("spec nesting depth", MAX_YAML_DEPTH, "lists and mappings inside each other, aliases followed"),
    ("entries of one YAML list or mapping", MAX_YAML_ITEMS, ""),
    ("YAML values after alias expansion", MAX_YAML_NODES, "refuses alias bombs ('billion laughs')"),
    ("integers in a spec", "2^63 - 1", ""),
    ("non-finite numbers (.inf, .nan)", "refused", "everywhere in a spec"),
    ("task.line.points", MAX_LINE_POINTS, ""),
    ("subtasks (avatars, landmarks, avatars along the line)", MAX_SUBTASKS, ""),
    ("episode steps (time_limit x control_hz)", f"1 to {MAX_EPISODE_STEPS:,}", ""),
    ("episode time limit, trajectory and pose-session time span", "one day (86,400 s)", "is the time in seconds?"),
    ("time between trajectory samples", "at least 1 microsecond", ""),
    ("organ mesh file (OBJ, STL)", f"{MAX_MESH_BYTES // 2**20} MiB", "a regular file"),
    ("trajectory file size", f"{MAX_TRAJECTORY_BYTES // 2**20} MiB", "on disk and decompressed"),
    ("trajectory samples", f"{MAX_TRAJECTORY_SAMPLES:,}", ""),
    ("trajectory metadata", f"{MAX_META_CHARS:,} characters, {MAX_META_DEPTH} deep", ""),
    ("portal coordinates", "joint range + (0.05 rad, 0.05 rad, 5 mm, 0.05 rad, 0.05 rad)", "else refused"),
    ("pose CSV size", f"{MAX_POSE_BYTES // 2**20} MiB", ""),
    ("pose CSV rows, and samples after resampling", f"{MAX_POSE_ROWS:,}", ""),
]


def open_regular(path, max_bytes: int) -> BinaryIO:
    """Open a regular file of at most max_bytes for reading; ValueError says why not (never blocks on a FIFO)."""
    try:
        fd = os.open(os.fspath(path), os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as e:
        raise ValueError(f"cannot read file: {e.strerror or e}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = "a folder" if stat.S_ISDIR(info.st_mode) else "not a regular file (a pipe, socket or device)"
            raise ValueError(f"cannot read file: it is {kind}")
        if info.st_size > max_bytes:
            raise ValueError(f"file is too large: {info.st_size:,} bytes, at most {max_bytes:,} are read")
    except BaseException:
        os.close(fd)
        raise
    # outside the try: once fdopen's file object holds the descriptor it closes it; closing it here too after a
    # Ctrl-C inside fdopen would close it twice, the second time perhaps another file's that took its number
    return os.fdopen(fd, "rb")
