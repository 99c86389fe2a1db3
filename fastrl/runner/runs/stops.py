"""How a run stops: Ctrl-C and SIGTERM alike, a full disk; what each leaves behind and how to go on."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ...atomic import DiskFull, free_bytes, megabytes

RESERVE_BYTES = 2_000_000  # kept free for closing the recording and writing meta.json when the disk fills


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived (a scheduler, `timeout` or `docker stop`): handled exactly like Ctrl-C."""


class RunInterrupted(Exception):
    """Training was stopped (Ctrl-C or SIGTERM); the run can be resumed."""

    def __init__(self, run: Path, timesteps: int, signal_name: str = "SIGINT"):
        super().__init__(f"interrupted at {timesteps} timesteps")
        self.run, self.timesteps, self.signal_name = run, timesteps, signal_name


class EvaluationInterrupted(Exception):
    """Evaluation was stopped (Ctrl-C or SIGTERM); the trained policy is saved in final/, resuming evaluates it."""

    def __init__(self, run: Path, signal_name: str = "SIGINT"):
        super().__init__("evaluation interrupted")
        self.run, self.signal_name = run, signal_name


class RunOutOfSpace(Exception):
    """The disk holding a run filled up; the run stopped cleanly and resumes once space is freed."""

    def __init__(self, run: Path, error: DiskFull, needed: int, recording_whole: bool):
        self.run, self.error, self.needed, self.recording_whole = run, error, needed, recording_whole
        super().__init__(self.sentence())

    def sentence(self) -> str:
        """One plain sentence: what could not be written, the space free and the space to free."""
        return (
            f"stopped: the disk holding {self.run} is full ({megabytes(self.error.free)} free) while writing "
            f"{self.error.path}; free at least {megabytes(self.needed)} there"
        )


def signal_name(stop: BaseException) -> str:
    """SIGTERM or SIGINT, from the KeyboardInterrupt a stop raised."""
    return "SIGTERM" if isinstance(stop, Terminated) else "SIGINT"


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_stopping = [False]  # a stop was raised and not yet handed back: set by _stop, cleared by stop_on_sigterm


def _stop(signum, frame) -> None:
    """SIGINT or SIGTERM: stop the main thread with KeyboardInterrupt (Terminated for SIGTERM)."""
    _stopping[0] = True
    raise Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


@contextmanager
def stop_on_sigterm(*, until_exit: bool = False) -> Iterator[None]:
    """While active, SIGINT and SIGTERM raise KeyboardInterrupt (SIGTERM: Terminated) in the main thread.

    Once a stop is caught and saving (`shielded`), later signals are ignored: a second Ctrl-C cannot cut the save
    short. Leaving, the handlers come back, unless a stop happened and `until_exit` (the command line, about to exit:
    a late Ctrl-C must not interrupt the interpreter's shutdown) or an enclosing stop_on_sigterm carries on."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, _stop) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        if _stopping[0] and (until_exit or previous[signal.SIGINT] is _stop):
            for s in STOP_SIGNALS:
                signal.signal(s, signal.SIG_IGN)
        else:
            for s, handler in previous.items():
                signal.signal(s, handler)
            _stopping[0] = False


@contextmanager
def shielded() -> Iterator[None]:
    """While active (saving the last checkpoint, closing the recording), SIGINT and SIGTERM are held off; after a
    stop they stay ignored until stop_on_sigterm ends (a first stop lost where Python ignores exceptions, as in an
    at-fork hook, leaves the handlers armed: the next signal stops)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = {s: signal.signal(s, signal.SIG_IGN) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        if not _stopping[0]:
            for s, handler in held.items():
                signal.signal(s, handler)


def tree_bytes(path: Path) -> int:
    """Total size of the files under a directory (0 if it does not exist)."""
    path = Path(path)
    if path.is_file():
        return path.stat().st_size
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) if path.is_dir() else 0


def space_to_resume(run: Path) -> int:
    """Bytes a resume needs: a new checkpoint, a rewritten copy of the recording, and the reserve."""
    ckpts = sorted(Path(run).glob("checkpoints/[0-9]*"))
    return (tree_bytes(ckpts[-1]) if ckpts else 0) + tree_bytes(Path(run) / "recording.rrd") + RESERVE_BYTES


def check_space(path: Path, needed: int) -> None:
    """Before writing `needed` bytes to `path`: raise DiskFull unless they and the reserve are free there."""
    free = free_bytes(path)
    if free is not None and free < needed + RESERVE_BYTES:
        raise DiskFull(Path(path), needed + RESERVE_BYTES, free)
