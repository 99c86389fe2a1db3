"""Crash-safe file writes (temporary file, fsync, rename) and the disk-full error; stdlib only, below every layer."""

from __future__ import annotations

import errno
import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import IO

SPACE_ERRNOS = (errno.ENOSPC, errno.EDQUOT)


class DiskFull(OSError):
    """Writing `path` failed for want of space: it needs `needed` bytes, `free` are free (either may be unknown)."""

    def __init__(self, path: Path, needed: int | None = None, free: int | None = None):
        self.path, self.needed = Path(path), needed
        self.free = free if free is not None else free_bytes(path)
        super().__init__(errno.ENOSPC, self.sentence())

    def __str__(self) -> str:
        """The sentence, without OSError's [Errno 28] prefix."""
        return self.sentence()

    def sentence(self) -> str:
        """One plain sentence naming the path, the space needed and the space free."""
        want = f"about {megabytes(self.needed)}" if self.needed else "more space"
        return f"the disk is full: writing {self.path} needs {want} and {megabytes(self.free)} are free"


def megabytes(n: int | None) -> str:
    """A byte count as a short human figure (MB, or kB below one MB)."""
    if n is None:
        return "? MB"
    return f"{n / 1e6:.1f} MB" if n >= 1e6 or n == 0 else f"{max(1, round(n / 1e3))} kB"


def free_bytes(path: Path) -> int | None:
    """Free bytes on the file system holding `path` (or its nearest existing parent), None if unknown."""
    p = Path(path)
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        return shutil.disk_usage(p).free
    except OSError:
        return None


def is_disk_full(exc: BaseException | None) -> bool:
    """Whether an exception (or one it was raised from or during) is ENOSPC or EDQUOT."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        if isinstance(exc, OSError) and exc.errno in SPACE_ERRNOS:
            return True
        exc = exc.__cause__ or exc.__context__
    return False


def fsync_dir(path: Path) -> None:
    """Make a rename or a new entry in a directory durable."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write(path: Path, write: Callable[[IO[bytes]], None], needed: int | None = None) -> Path:
    """write(f) to a temporary file beside `path`, fsync, rename over `path`: a kill leaves the old file or the new."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with open(tmp, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as e:
        tmp.unlink(missing_ok=True)
        if is_disk_full(e):
            raise DiskFull(path, needed) from None
        raise
    fsync_dir(path.parent)
    return path


def write_text(path: Path, text: str) -> Path:
    """Write a text file atomically (UTF-8)."""
    data = text.encode("utf-8")
    return atomic_write(path, lambda f: f.write(data), needed=len(data))


def write_json(path: Path, obj) -> Path:
    """Write an indented JSON file atomically."""
    return write_text(path, json.dumps(obj, indent=2))


def append_line(path: Path, line: str) -> None:
    """Append one line to a log (metrics.jsonl) and fsync it; a kill may tear it, so readers skip bad lines."""
    data = (line.rstrip("\n") + "\n").encode("utf-8")
    try:
        with open(path, "ab") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
    except OSError as e:
        if is_disk_full(e):
            raise DiskFull(Path(path), len(data)) from None
        raise


def ensure_space(path: Path, needed: int) -> None:
    """Raise DiskFull if the file system holding `path` has fewer than `needed` free bytes."""
    free = free_bytes(path)
    if free is not None and free < needed:
        raise DiskFull(Path(path), needed, free)
