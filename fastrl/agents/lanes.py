"""Shared memory between this process and a forked env worker: a step's actions in, its results out, no pipe."""

from __future__ import annotations

import mmap
import pickle
import time
from collections.abc import Callable

import numpy as np

from .. import forked

STEP, COMMAND = 1, 2  # what the parent posted: a step's actions, or a command waiting in the pipe
INFO_BYTES = 1 << 22  # room for a step's pickled infos (16 TraceLines envs: 4 KB); larger ones go by the pipe


def shared(shape: tuple, dtype) -> np.ndarray:
    """A zeroed array in anonymous shared memory: a child forked after this sees and writes the same bytes."""
    dtype = np.dtype(dtype)
    count = int(np.prod(shape, dtype=np.int64))
    return np.frombuffer(mmap.mmap(-1, max(1, count * dtype.itemsize)), dtype, count).reshape(shape)


def acquire(sem, spin: float, alive: Callable[[], bool]) -> bool:
    """Take `sem`: polled for `spin` seconds, then asleep, looking every WATCH_SECONDS whether the other side is
    `alive()` (False: it is gone)."""
    deadline = time.perf_counter() + spin
    while not sem.acquire(False):
        if time.perf_counter() >= deadline:
            while not sem.acquire(timeout=forked.WATCH_SECONDS):
                if not alive():
                    return False
            return True
    return True


class Lane:
    """One worker's step through shared memory: a semaphore wakes it, it writes observations, rewards and dones
    into arrays and its infos pickled into a buffer, and a second semaphore wakes this process. A pipe write and
    read per step cost 0.04 and 0.15 ms on a 2-core VM (a system call and a wake-up each), these a few
    microseconds. Commands other than a step still go by the pipe, announced on the same semaphore."""

    def __init__(self, *, ctx, n: int, obs_space, action_space):
        self.actions = shared((n, *action_space.shape), action_space.dtype)
        self.obs = shared((n, *obs_space.shape), obs_space.dtype)
        self.rews = shared((n,), np.float32)
        self.dones = shared((n,), np.bool_)
        self.head = shared((2,), np.int64)  # what was posted; the infos' pickled length (-1: sent by the pipe)
        self.info = shared((INFO_BYTES,), np.uint8)
        self.go, self.done = ctx.Semaphore(0), ctx.Semaphore(0)

    def post_step(self, actions: np.ndarray) -> None:
        """Parent: hand the worker a step's actions."""
        self.actions[:] = actions
        self.head[0] = STEP
        self.go.release()

    def post_command(self) -> None:
        """Parent: tell the worker a command waits in the pipe."""
        self.head[0] = COMMAND
        self.go.release()

    def next_is_step(self, spin: float, alive: Callable[[], bool]) -> bool | None:
        """Worker: wait for the parent's next post; whether it is a step (None: the parent is gone)."""
        if not acquire(self.go, spin, alive):
            return None
        return bool(self.head[0] == STEP)

    def put(self, results: tuple, conn) -> None:
        """Worker: publish a step's (obs, rewards, dones, infos)."""
        obs, rews, dones, infos = results
        self.obs[:], self.rews[:], self.dones[:] = obs, rews, dones
        blob = pickle.dumps(infos, protocol=pickle.HIGHEST_PROTOCOL)
        if len(blob) <= INFO_BYTES:
            self.info[: len(blob)] = np.frombuffer(blob, np.uint8)
            self.head[1] = len(blob)
            self.done.release()
        else:  # the parent reads the pipe once told: a large message would otherwise fill the pipe first
            self.head[1] = -1
            self.done.release()
            conn.send(infos)

    def take(self, spin: float, alive: Callable[[], bool], conn) -> tuple:
        """Parent: the worker's step results, once they are there (EOFError if the worker died)."""
        if not acquire(self.done, spin, alive):
            raise EOFError("an env worker process ended")
        n = int(self.head[1])
        # written by our own forked worker into memory only it and this process map: what the pipe's recv unpickles
        infos = pickle.loads(self.info[:n]) if n >= 0 else conn.recv()
        return self.obs.copy(), self.rews.copy(), self.dones.copy(), infos
