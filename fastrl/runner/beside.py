"""Work done beside this process: a forked child computes a result while this process goes on."""

from __future__ import annotations

import multiprocessing as mp
import signal
from collections.abc import Callable
from typing import Any

STOPS = {signal.SIGINT, signal.SIGTERM}


class ChildFailed(RuntimeError):
    """The forked child ended without a result (killed, or out of memory)."""


def _compute(fn: Callable[[], Any], out, parent_end) -> None:
    """The child: ignore Ctrl-C (the parent decides), compute, send (ok, value or exception), exit."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # the parent's cancel() or exit ends it: quietly
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOPS)
    parent_end.close()
    try:
        result = (True, fn())
    except Exception as error:  # noqa: BLE001 - handed to the parent, which raises it
        result = (False, error)
    try:
        out.send(result)
    except OSError:  # BrokenPipeError: the parent stopped waiting (a stop, a cancel): there is no one to tell
        pass
    finally:
        out.close()


class Beside:
    """`fn()` computed in a forked child from now on; `result()` waits for it, `cancel()` stops it.

    Where this platform cannot fork, or `fork` is false, `fn()` runs here when `result()` asks for it."""

    def __init__(self, fn: Callable[[], Any], *, fork: bool = True):
        self.fn, self.child = fn, None
        if fork and "fork" in mp.get_all_start_methods():
            ctx = mp.get_context("fork")
            self.here, there = ctx.Pipe(duplex=False)
            self.child = ctx.Process(target=_compute, args=(fn, there, self.here), daemon=True)
            held = signal.pthread_sigmask(signal.SIG_BLOCK, STOPS)  # a stop during fork() comes after it, not inside
            try:  # the at-fork hooks, where Python would print it and carry on
                self.child.start()
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, held)
            there.close()

    def result(self) -> Any:
        """The value of fn() (its exception, if it raised)."""
        if self.child is None:
            return self.fn()
        try:
            ok, value = self.here.recv()
        except EOFError:
            raise ChildFailed(f"the process computing {getattr(self.fn, '__name__', 'a result')} died") from None
        finally:
            self.child.join(timeout=5.0)
            self.cancel()
        if not ok:
            raise value
        return value

    def cancel(self) -> None:
        """Stop the child if it still runs and release its pipe (after this, `result()` computes here)."""
        if self.child is None:
            return
        if self.child.is_alive():
            self.child.kill()
        self.child.join()
        self.here.close()
        self.child = None
