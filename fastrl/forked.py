"""The one way fastrl runs work in another process: forked, stops held during fork, Ctrl-C left to the parent."""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import signal
import threading
import time
import weakref
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

STOPS = {signal.SIGINT, signal.SIGTERM}
WATCH_SECONDS = 0.5  # how often a child that must not outlive its parent looks for it
_IDLE_WORKERS: weakref.WeakSet = weakref.WeakSet()  # this process's workers at the lowest priority


class ChildFailed(RuntimeError):
    """The child process ended without a result (killed, or out of memory)."""


def can_fork() -> bool:
    """Whether this platform forks (the children inherit this process's objects: nothing is pickled)."""
    return "fork" in mp.get_all_start_methods()


def context(fork: bool = True):
    """The fork context, or where this platform cannot fork or `fork` is false, a fresh process's (the forkserver's,
    else spawn's: what the child runs must pickle)."""
    if fork and can_fork():
        return mp.get_context("fork")
    return mp.get_context("forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn")


@contextlib.contextmanager
def stops_held() -> Iterator[None]:
    """SIGINT and SIGTERM held back meanwhile: a stop during fork() comes after it, not inside the at-fork hooks,
    where Python would print it and carry on."""
    held = signal.pthread_sigmask(signal.SIG_BLOCK, STOPS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """While active (a periodic checkpoint being written, a GL call), SIGINT and SIGTERM wait: the first is raised
    again, with the handlers of before, once the block is done, so that no stop cuts a file short mid-write or comes
    out of a C library's callback as another error. Python runs handlers in the main thread: elsewhere, nothing
    waits."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    held = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s in STOPS}
    try:
        yield
    finally:
        for s, handler in held.items():
            signal.signal(s, handler)
        if caught:
            signal.raise_signal(caught[0])


def start(process) -> None:
    """Start a multiprocessing Process with stops held during its fork."""
    with stops_held():
        process.start()


def child_signals(*, term=signal.SIG_DFL) -> None:
    """In the child: Ctrl-C is the parent's to handle (it reaches the whole process group); SIGTERM does `term`
    (SIG_DFL: a cancel or the parent's exit ends it quietly; SIG_IGN: the parent stops it by closing its pipe)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, term)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOPS)


def close_ends(ends) -> None:
    """In the child: close the parent's pipe ends inherited by the fork, so that a pipe reads as closed (EOF) once
    the parent dies or closes its end."""
    for end in ends:
        end.close()


def _watch(parent: int) -> None:
    """A child's watch: exit at once when the parent is gone (a killed parent never reads the result)."""
    while os.getppid() == parent:
        time.sleep(WATCH_SECONDS)
    os._exit(0)


def lowest_priority() -> None:
    """This process runs only on CPU time no other process wants (Linux's SCHED_IDLE; elsewhere nice 19)."""
    if hasattr(os, "SCHED_IDLE"):
        os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    else:
        os.nice(19)


def idle_work_running() -> bool:
    """Whether a worker of this process at the lowest priority is computing: CPU time left unused is its."""
    return any(w.computing() for w in list(_IDLE_WORKERS))


def _begin(parent: int, term, orphan_exit: bool, idle: bool, initializer: Callable | None, initargs: tuple) -> None:
    """A worker's start: the child's signals and priority, its watch on the parent if asked, then the caller's
    initializer."""
    child_signals(term=term)
    if idle:
        lowest_priority()
    if orphan_exit:
        threading.Thread(target=_watch, args=(parent,), daemon=True, name="fastrl-watch").start()
    if initializer is not None:
        initializer(*initargs)


class Worker:
    """One forked worker process behind a ProcessPoolExecutor: `submit` work, `kill` it, or `shutdown` when done.

    `initializer(*initargs)` runs in the child first and is inherited, not pickled: it may hand over lambdas, a
    scorer with its networks, a shared counter. With `orphan_exit`, the child exits as soon as this process dies;
    with `idle`, it runs at the lowest priority (on the CPU time this process and the others leave)."""

    def __init__(
        self,
        *,
        initializer: Callable | None = None,
        initargs: tuple = (),
        term=signal.SIG_DFL,
        orphan_exit: bool = False,
        idle: bool = False,
    ):
        self.pool = ProcessPoolExecutor(
            1,
            mp_context=context(),
            initializer=_begin,
            initargs=(os.getpid(), term, orphan_exit, idle, initializer, initargs),
        )
        self.process, self.futures = None, []
        if idle:
            _IDLE_WORKERS.add(self)

    def submit(self, fn: Callable, *args) -> Future:
        """Run a picklable function in the worker; the first call forks it, stops held."""
        if self.process is not None:
            future = self.pool.submit(fn, *args)
        else:
            with stops_held():
                future = self.pool.submit(fn, *args)
                (self.process,) = self.pool._processes.values()  # forked by the first submit (fork: all at once)
        self.futures = [*(f for f in self.futures if not f.done()), future]
        return future

    def computing(self) -> bool:
        """Whether work submitted to the worker is still pending or running."""
        return self.process is not None and any(not f.done() for f in self.futures)

    def kill(self) -> None:
        """Kill the worker if it still runs, wait for it, and cancel what was pending."""
        if self.process is not None and self.process.is_alive():
            self.process.kill()
        if self.process is not None:
            self.process.join()
        self.pool.shutdown(wait=True, cancel_futures=True)
        self.futures = []

    def shutdown(self) -> None:
        """Let the worker finish what it runs, cancel what is pending, and wait for it to exit."""
        self.pool.shutdown(wait=True, cancel_futures=True)


def outcome(future: Future, what: str):
    """The future's value (its exception, if it raised); ChildFailed if the worker died before it answered."""
    try:
        return future.result()
    except BrokenProcessPool:
        raise ChildFailed(f"the process computing {what} died") from None
