"""Work done beside this process: a forked child computes a result while this process goes on."""

from __future__ import annotations

import os
import pickle
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ...forked import ChildFailed, Worker, can_fork, outcome

__all__ = ["Beside", "ChildFailed", "child_or_here"]

_FN: Callable[[], Any] | None = None  # the child's copy of the function it computes


def _keep(fn: Callable[[], Any]) -> None:
    """Child start: keep the inherited function (a lambda need not pickle)."""
    global _FN
    _FN = fn


def _compute(path: str) -> None:
    """The child's one job: fn(), its value written to `path` (its exception sent back to the parent). Not sent
    through the pool's pipe: a child killed halfway through a large message would leave the parent's reader
    waiting for the rest forever (the parent holds the pipe's other end), and a stop could not end it."""
    value = _FN()
    with open(path, "wb") as f:
        pickle.dump(value, f, protocol=pickle.HIGHEST_PROTOCOL)


class Beside:
    """`fn()` computed in a forked child from now on; `result()` waits for it, `cancel()` stops it.

    The child ignores Ctrl-C (the parent decides), ends quietly on SIGTERM or a cancel, and exits as soon as this
    process dies. With `idle`, it runs only on CPU time no other process wants (on a busy machine it may wait long:
    see `done`). Where this platform cannot fork, or `fork` is false, `fn()` runs here when `result()` asks."""

    def __init__(self, fn: Callable[[], Any], *, fork: bool = True, idle: bool = False):
        self.fn, self.worker, self.child, self.path, self.known = fn, None, None, None, False
        if fork and can_fork():
            handle, self.path = tempfile.mkstemp(prefix="fastrl-beside-", suffix=".pickle")  # this user's only
            os.close(handle)
            self.worker = Worker(initializer=_keep, initargs=(fn,), orphan_exit=True, idle=idle)
            self.future = self.worker.submit(_compute, self.path)
            self.child = self.worker.process

    @classmethod
    def ready(cls, value: Any) -> Beside:
        """A job whose value is already known: done, nothing forked."""
        job = cls(lambda: value, fork=False)
        job.known = True
        return job

    def result(self) -> Any:
        """The value of fn() (its exception, if it raised)."""
        if self.worker is None:
            return self.fn()
        try:
            outcome(self.future, getattr(self.fn, "__name__", "a result"))
            with open(self.path, "rb") as f:
                return pickle.load(f)  # written by our child into a file only this user can write
        finally:
            self.cancel()

    def done(self) -> bool:
        """Whether the child has its result ready (False where `fn()` runs here, unless known from the start)."""
        return self.known or (self.worker is not None and self.future.done())

    def cancel(self) -> None:
        """Stop the child if it still runs and release it (after this, `result()` computes here)."""
        if self.worker is None:
            return
        self.worker.kill()
        self.worker, self.child = None, None
        Path(self.path).unlink(missing_ok=True)


def child_or_here(job: Beside, fn: Callable[[], Any]) -> Any:
    """The child's result; fn() here if the child died (killed, out of memory)."""
    try:
        return job.result()
    except ChildFailed:
        return fn()
