"""Vectorised envs split across processes: this one steps a batch of envs while worker processes step the rest."""

from __future__ import annotations

import os
import signal
import socket
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv

from .. import forked
from .lanes import Lane


class FreshInfoVecEnv(DummyVecEnv):
    """DummyVecEnv without the deep copy of infos: FastEnv builds fresh info dicts every step."""

    def step_wait(self):
        """Step every env, resetting finished ones, in SB3's VecEnv convention."""
        for i, env in enumerate(self.envs):
            obs, self.buf_rews[i], terminated, truncated, info = env.step(self.actions[i])
            self.buf_dones[i] = terminated or truncated
            info["TimeLimit.truncated"] = truncated and not terminated
            if self.buf_dones[i]:
                info["terminal_observation"] = obs
                obs, self.reset_infos[i] = env.reset()
            self.buf_infos[i] = info
            self._save_obs(i, obs)
        return self._obs_from_buf(), np.copy(self.buf_rews), np.copy(self.buf_dones), list(self.buf_infos)


SPIN = 0.002  # seconds a process polls a pipe before it sleeps in the read


def recv_soon(conn, spin: float = SPIN):
    """The next message, polled for up to `spin` seconds before blocking: a process asleep in a read took 0.09 ms
    (median; 0.19 at p90) to wake up on a 2-core VM, a tenth of a 16-env batch's step. Rollout steps come 0.6 ms
    apart, so a worker stays awake through a rollout and sleeps through a PPO update."""
    deadline = time.perf_counter() + spin
    while not conn.poll() and time.perf_counter() < deadline:
        pass
    return conn.recv()


def _closed(peer: socket.socket) -> bool:
    """Whether the parent's end of the pipe is closed (its SplitVecEnv collected, or the parent gone), unread."""
    try:
        return peer.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b""
    except BlockingIOError:
        return False
    except OSError:
        return True


def _serve(conn, parent_ends: list, make_env: Callable[[], gym.Env], n: int, spin: float, lane: Lane | None) -> None:
    """A worker's loop: step, reset and query its batch of envs on the parent's commands until told to stop.

    It ignores SIGINT and SIGTERM (a Ctrl-C reaches the whole process group; the parent decides and then closes
    the pipe) and ends when the pipe closes, so it never outlives its parent. The parent's ends of the pipes,
    inherited by the fork, are closed first: else the pipe would never read as closed. It polls for each command
    for `spin` seconds before it sleeps. With a `lane`, steps come and go through shared memory and other commands
    by the pipe; asleep, it looks every WATCH_SECONDS whether the pipe was closed or its parent is gone.
    """
    forked.child_signals(term=signal.SIG_IGN)
    forked.close_ends(parent_ends)
    venv = FreshInfoVecEnv([make_env for _ in range(n)])
    parent = os.getppid()
    peer = socket.fromfd(conn.fileno(), socket.AF_UNIX, socket.SOCK_STREAM) if lane is not None else None
    try:
        while True:
            if lane is not None:
                step = lane.next_is_step(spin, lambda: os.getppid() == parent and not _closed(peer))
                if step is None:
                    break
                if step:
                    venv.step_async(lane.actions.copy())
                    lane.put(venv.step_wait(), conn)
                    continue
                command, arg = conn.recv()
            else:
                command, arg = recv_soon(conn, spin)
            if command == "step":
                venv.step_async(arg)
                conn.send(venv.step_wait())
            elif command == "reset":
                venv._seeds, venv._options = arg
                obs = venv.reset()
                conn.send((obs, venv.reset_infos))
            elif command == "get_attr":
                conn.send(venv.get_attr(arg))
            elif command == "set_attr":
                conn.send(venv.set_attr(*arg))
            elif command == "env_method":
                name, args, kwargs = arg
                conn.send(venv.env_method(name, *args, **kwargs))
            elif command == "env_is_wrapped":
                conn.send(venv.env_is_wrapped(arg))
            else:  # "close"
                break
    except (EOFError, BrokenPipeError, ConnectionResetError):  # the parent is gone
        pass
    finally:
        venv.close()
        conn.close()
        if peer is not None:
            peer.close()


class SplitVecEnv(VecEnv):
    """`n_envs` envs stepped by `processes` processes: this one holds the first batch, each worker one more.

    Env i behaves as env i of a FreshInfoVecEnv of the same envs (same seeds, same order of results), so the
    split changes the speed, never the trajectories. Workers are forked daemons that ignore Ctrl-C and SIGTERM
    and exit when the pipe to this process closes. The processes poll for each other's messages before they sleep
    (`recv_soon`), unless they start while work at the lowest priority runs beside them: the CPU time they would
    poll away is its (`fastrl run`'s scripted expert: 2.5 s later to the final evaluation, 0.7 s sooner training).
    """

    def __init__(self, *, make_env: Callable[[], gym.Env], n_envs: int, processes: int, fork: bool = True):
        """`fork: false` starts workers from a fresh process (forkserver or spawn; `make_env` must pickle): a child
        forked after this process rendered would deadlock in Mesa's EGL as soon as it rendered itself."""
        batches = [len(b) for b in np.array_split(np.arange(n_envs), max(1, min(processes, n_envs)))]
        self.local = FreshInfoVecEnv([make_env for _ in range(batches[0])])
        ctx = forked.context(fork)
        self.batches, self.pipes, self.procs = batches, [], []
        self.spin = 0.0 if forked.idle_work_running() else SPIN
        space, actions = self.local.observation_space, self.local.action_space
        self.lanes = None  # shared memory where a forked child inherits it and the observations are one array
        if ctx.get_start_method() == "fork" and isinstance(space, gym.spaces.Box):
            self.lanes = [Lane(ctx=ctx, n=n, obs_space=space, action_space=actions) for n in batches[1:]]
        for i, n in enumerate(batches[1:]):
            parent, child = ctx.Pipe()
            ends = [*self.pipes, parent] if ctx.get_start_method() == "fork" else []
            args = (child, ends, make_env, n, self.spin, self.lanes[i] if self.lanes else None)
            proc = ctx.Process(target=_serve, args=args, daemon=True, name="fastrl-envs")
            forked.start(proc)
            child.close()
            self.pipes.append(parent)
            self.procs.append(proc)
        self.waiting = False
        self.closed = False
        super().__init__(n_envs, self.local.observation_space, self.local.action_space)

    def _slices(self) -> list[slice]:
        """The env indices of each process's batch, this process's first."""
        ends = np.cumsum(self.batches)
        return [slice(int(e - n), int(e)) for n, e in zip(self.batches, ends)]

    def _send(self, i: int, message: tuple) -> None:
        """A command to worker i by its pipe (announced in its lane, if it has one)."""
        self.pipes[i].send(message)
        if self.lanes:
            self.lanes[i].post_command()

    def _ask(self, command: str, arg=None) -> list:
        """Send one command to every worker and collect their answers, in order."""
        for i in range(len(self.pipes)):
            self._send(i, (command, arg))
        return [pipe.recv() for pipe in self.pipes]

    def step_async(self, actions: np.ndarray) -> None:
        """Hand each worker its actions; this process steps its own batch in step_wait meanwhile."""
        parts = self._slices()
        for i, part in enumerate(parts[1:]):
            if self.lanes:
                self.lanes[i].post_step(actions[part])
            else:
                self.pipes[i].send(("step", actions[part]))
        self.waiting = True
        self.local.step_async(actions[parts[0]])

    def step_wait(self):
        """Step this process's batch, then gather the workers' results."""
        results = [self.local.step_wait()]
        if self.lanes:
            results += [lane.take(self.spin, p.is_alive, c) for lane, p, c in zip(self.lanes, self.procs, self.pipes)]
        else:
            results += [recv_soon(pipe, self.spin) for pipe in self.pipes]
        self.waiting = False
        obs, rews, dones, infos = zip(*results)
        return np.concatenate(obs), np.concatenate(rews), np.concatenate(dones), [i for part in infos for i in part]

    def reset(self):
        """Reset every env with the pending seeds and options."""
        parts = self._slices()
        for i, part in enumerate(parts[1:]):
            self._send(i, ("reset", (self._seeds[part], self._options[part])))
        self.local._seeds, self.local._options = self._seeds[parts[0]], self._options[parts[0]]
        obs = [self.local.reset()]
        infos = [self.local.reset_infos]
        for pipe in self.pipes:
            o, i = pipe.recv()
            obs.append(o)
            infos.append(i)
        self.reset_infos = [i for part in infos for i in part]
        self._reset_seeds()
        self._reset_options()
        return np.concatenate(obs)

    def close(self) -> None:
        """Stop the workers (draining a step in flight, as after Ctrl-C) and wait for them."""
        if self.closed:
            return
        self.closed = True
        for i, pipe in enumerate(self.pipes):
            try:
                if self.waiting:  # a step stopped by Ctrl-C: its answer, before the command
                    if self.lanes:
                        self.lanes[i].done.acquire(timeout=10)
                    elif pipe.poll(10):
                        pipe.recv()
                self._send(i, ("close", None))
            except (EOFError, BrokenPipeError, ConnectionResetError):
                pass
            pipe.close()
        for proc in self.procs:
            proc.join(timeout=5)
            if proc.is_alive():
                proc.terminate()
                proc.join()
        self.local.close()

    def _split(self, indices) -> list[list[int]]:
        """Global env indices per process, as each process's local indices."""
        wanted = set(self._get_indices(indices))
        return [[i - p.start for i in range(p.start, p.stop) if i in wanted] for p in self._slices()]

    def get_attr(self, attr_name: str, indices=None) -> list:
        """An attribute of each env."""
        if not hasattr(self, "local"):
            return []
        picked = self._split(indices)
        out = self.local.get_attr(attr_name, picked[0])
        for i, (pipe, local) in enumerate(zip(self.pipes, picked[1:])):
            self._send(i, ("get_attr", attr_name))
            values = pipe.recv()
            out += [values[i] for i in local]
        return out

    def set_attr(self, attr_name: str, value, indices=None) -> None:
        """Set an attribute on each env."""
        picked = self._split(indices)
        self.local.set_attr(attr_name, value, picked[0])
        for i, (pipe, local) in enumerate(zip(self.pipes, picked[1:])):
            if local:
                self._send(i, ("set_attr", (attr_name, value, local)))
                pipe.recv()

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list:
        """Call a method of each env."""
        picked = self._split(indices)
        out = self.local.env_method(method_name, *method_args, indices=picked[0], **method_kwargs)
        for i, (pipe, local) in enumerate(zip(self.pipes, picked[1:])):
            if local:
                self._send(i, ("env_method", (method_name, method_args, {**method_kwargs, "indices": local})))
                out += pipe.recv()
        return out

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        """Whether each env is wrapped by the class."""
        picked = self._split(indices)
        out = self.local.env_is_wrapped(wrapper_class, picked[0])
        for i, (pipe, local) in enumerate(zip(self.pipes, picked[1:])):
            self._send(i, ("env_is_wrapped", wrapper_class))
            values = pipe.recv()
            out += [values[i] for i in local]
        return out

    def get_images(self):
        """Not rendered during training."""
        raise NotImplementedError("SplitVecEnv does not render")
