"""An append-only JSON-lines journal of scored files, so an interrupted `fastrl score` resumes where it stopped.

Its first line names what scored (the spec, the networks, fastrl's version); every other line is one file's
scalars (or why it was not scored), keyed by its path, size and modification time. Each line is one `os.write` on
an O_APPEND descriptor, so two processes may append to one journal; lines are fsynced in batches."""

from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np

from ..about import VERSION
from .scoring import TrajectoryScores

FORMAT = 1
SYNC_EVERY = 64  # lines between fsyncs (and at most SYNC_SECONDS apart): a kill loses none, a power cut a batch
SYNC_SECONDS = 2.0
STAMP = ("size", "mtime_ns")


def identity(spec: Path, networks: Path | None) -> str:
    """A checksum of the spec file and the networks' files (not their loaded tensors: torch is not imported)."""
    h = hashlib.sha256(f"fastrl {VERSION}\n".encode())
    for f in [Path(spec)] + (sorted(p for p in Path(networks).iterdir() if p.is_file()) if networks else []):
        h.update(f"{f.name}\n".encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:32]


def stamp(path: Path) -> dict:
    """The file's size and modification time (None for both where it cannot be read)."""
    try:
        st = os.stat(path)
    except OSError:
        return {"size": None, "mtime_ns": None}
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns}


def record(path: Path, scored: TrajectoryScores | None = None, problem: str | None = None) -> dict:
    """One journal line: a file's stamp and its raw scalar scores and labels, or the problem naming it."""
    line = {"file": str(path), **stamp(path)}
    if scored is None:
        return line | {"problem": problem}
    return line | {"name": scored.name, "meta": scored.meta, "scores": scored.scores}


def slim(line: dict) -> TrajectoryScores:
    """The scores of a journal line, without the per-sample arrays (the report needs none)."""
    return TrajectoryScores(line["name"], line["meta"], dict(line["scores"]), np.empty(0), np.empty((0, 3)))


class Journal:
    """The journal at `path` of one scorer (`identity`); reading it drops a torn last line and another scorer's."""

    def __init__(self, *, path: Path, identity: str):
        self.path, self.identity = Path(path), identity
        self.fd: int | None = None
        self.unsynced, self.synced_at = 0, time.monotonic()
        self.notes: list[str] = []

    def lines(self) -> list[dict]:
        """Every whole line of this scorer's journal (none if it is missing, unreadable or another scorer's)."""
        try:
            text = self.path.read_text()
        except (OSError, UnicodeDecodeError):
            return []
        out, header = [], None
        for raw in text.splitlines():
            try:
                line = json.loads(raw)
            except json.JSONDecodeError:
                continue  # a line cut by a kill: its file is scored again
            if header is None:
                header = line
                if not isinstance(line, dict) or line.get("identity") != self.identity:
                    self.notes.append(
                        f"{self.path} was written by another scorer (spec, networks or version): scoring afresh"
                    )
                    return []
            elif isinstance(line, dict) and "file" in line:
                out.append(line)
        return out

    def done(self, files: list[Path]) -> dict[str, dict]:
        """The latest line of each of `files` whose size and modification time are those journaled."""
        wanted = {str(f) for f in files}
        latest = {line["file"]: line for line in self.lines() if line["file"] in wanted}
        return {f: line for f, line in latest.items() if stamp(Path(f)) == {k: line.get(k) for k in STAMP}}

    def open(self, fresh: bool = False) -> Journal:
        """Open for appending (a new journal if `fresh`, missing or another scorer's); returns itself."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        keep = not fresh and self.path.exists() and self._header_ok()
        flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | (0 if keep else os.O_TRUNC)
        self.fd = os.open(self.path, flags, 0o644)
        if not keep:
            self._write({"journal": FORMAT, "identity": self.identity})
        elif not _ends_a_line(self.path):
            os.write(self.fd, b"\n")  # after a torn line, the next starts on its own
        return self

    def append(self, line: dict) -> None:
        """Add one line (one write, so lines from two processes never interleave); fsync every batch."""
        self._write(line)
        self.unsynced += 1
        if self.unsynced >= SYNC_EVERY or time.monotonic() - self.synced_at > SYNC_SECONDS:
            self.sync()

    def sync(self) -> None:
        """Flush the appended lines to the disk."""
        if self.fd is not None and self.unsynced:
            os.fsync(self.fd)
        self.unsynced, self.synced_at = 0, time.monotonic()

    def close(self) -> None:
        """Sync and close (again: nothing)."""
        if self.fd is not None:
            self.sync()
            os.close(self.fd)
            self.fd = None

    def _header_ok(self) -> bool:
        """Whether the first line names this scorer."""
        try:
            with self.path.open() as f:
                return json.loads(f.readline()).get("identity") == self.identity
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, AttributeError):
            return False

    def _write(self, line: dict) -> None:
        """One JSON line in one write."""
        os.write(self.fd, (json.dumps(line, default=float) + "\n").encode())


def _ends_a_line(path: Path) -> bool:
    """Whether a file is empty or its last byte is a newline (read alone, not the whole file)."""
    with path.open("rb") as f:
        if f.seek(0, os.SEEK_END) == 0:
            return True
        f.seek(-1, os.SEEK_END)
        return f.read(1) == b"\n"
