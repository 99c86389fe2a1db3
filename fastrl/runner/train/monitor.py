"""Training callbacks, one job each: episode tally, progress bar, evaluations, curve points, checkpoints, stop."""

from __future__ import annotations

import json
import math
import shutil
import time
from collections import deque
from collections.abc import Callable
from operator import itemgetter
from pathlib import Path

import numpy as np
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from stable_baselines3.common.callbacks import BaseCallback, CallbackList
from stable_baselines3.common.vec_env import VecNormalize

from ...agents.sb3 import save_checkpoint
from ...atomic import append_line
from ...forked import deferred
from ..runs.stops import check_space, tree_bytes


class SessionRate(BaseCallback):
    """A callback that knows the training steps per second since this session's training started."""

    def _on_training_start(self) -> None:
        self.start_steps, self.started = self.num_timesteps, time.perf_counter()

    def rate(self) -> float:
        """Training steps per second in this session."""
        return (self.num_timesteps - self.start_steps) / max(1e-9, time.perf_counter() - self.started)


class EpisodeTally(BaseCallback):
    """Per-episode return, success, subtask share, time and reward features from the env infos."""

    def __init__(self, *, feature_names: list[str], episodes: int = 0):
        super().__init__()
        self.names, self.episodes = feature_names, episodes
        self.recent: deque[dict] = deque(maxlen=100)
        self.window: list[dict] = []  # the episodes since the last curve point

    def _on_training_start(self) -> None:
        n = self.training_env.num_envs
        self.ret, self.feats = np.zeros(n), np.zeros((n, len(self.names)))
        self.pick = itemgetter(*self.names) if len(self.names) > 1 else lambda f: (f[self.names[0]],)

    def _on_step(self) -> bool:
        env = self.training_env
        rewards = env.get_original_reward() if isinstance(env, VecNormalize) else self.locals["rewards"]
        self.ret += rewards
        infos = self.locals["infos"]
        self.feats += [self.pick(info["features"]) for info in infos]
        for i in np.flatnonzero(self.locals["dones"]):
            info = infos[i]
            ep = {
                "return": float(self.ret[i]),
                "success": float(info["success"]),
                "subtasks": info["subtask"] / max(1, info["subtasks_total"]),
                "time": info["time"],
                "features": self.feats[i].copy(),
            }
            self.recent.append(ep)
            self.window.append(ep)
            self.episodes += 1
            self.ret[i], self.feats[i] = 0.0, 0.0
        return True

    def take_window(self) -> list[dict]:
        """The episodes since the last call (none: the latest ten), and a new window."""
        eps = self.window or list(self.recent)[-10:]
        self.window = []
        return eps


class ProgressBar(SessionRate):
    """The rich progress bar: timesteps, steps/s and the latest point's success and subtasks."""

    def __init__(self, *, total: int, enabled: bool = True):
        super().__init__()
        self.total, self.next_tick, self.task_id = total, 0, None
        self.bar = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[rate]:>6} steps/s"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            TextColumn("{task.fields[status]}"),
            disable=not enabled,
        )

    def _on_training_start(self) -> None:
        super()._on_training_start()
        self.bar.start()
        self.task_id = self.bar.add_task(
            "training", total=self.total, completed=self.num_timesteps, rate="-", status=""
        )

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.next_tick:
            self.next_tick += 2048
            self.bar.update(self.task_id, completed=self.num_timesteps, rate=f"{self.rate():.0f}")
        return True

    def status(self, text: str) -> None:
        """Show a word beside the bar (e.g. while an evaluation runs)."""
        self.bar.update(self.task_id, status=text)

    def show_point(self, timesteps: int, m: dict) -> None:
        """Show a curve point: its steps/s, success and subtask share."""
        ok = "episode/success_rate" in m
        status = f"success {m['episode/success_rate']:.0%}  subtasks {m['episode/subtasks']:.0%}" if ok else ""
        self.bar.update(self.task_id, completed=timesteps, rate=f"{m['fps']:.0f}", status=status)

    def stop(self) -> None:
        """Take the bar off the terminal."""
        self.bar.stop()

    def _on_training_end(self) -> None:
        self.stop()


class PeriodicEvaluation(BaseCallback):
    """Every `every` timesteps, run `evaluator()`; its figures of this step are in `latest` (else empty)."""

    def __init__(self, *, evaluator: Callable[[], dict], every: int, status: Callable[[str], None] | None = None):
        super().__init__()
        self.evaluator, self.every, self.status = evaluator, every, status
        self.latest: dict = {}

    def _on_training_start(self) -> None:
        self.next_eval = self.num_timesteps + self.every

    def _on_step(self) -> bool:
        self.latest = {}
        if self.num_timesteps >= self.next_eval:
            if self.status is not None:
                self.status("evaluating")
            self.latest = self.evaluator()
            self.next_eval += self.every
        return True


class CurvePoints(SessionRate):
    """Every `log_every` timesteps (and after each evaluation) a curve point to metrics.jsonl and the sinks."""

    def __init__(
        self,
        *,
        run: Path,
        tally: EpisodeTally,
        log_every: int,
        evaluation: PeriodicEvaluation | None = None,
        stats: Callable[[], dict] | None = None,
        sinks: list[Callable[[int, dict], None]] = (),
    ):
        super().__init__()
        self.run, self.tally, self.log_every = run, tally, log_every
        self.evaluation, self.stats, self.sinks = evaluation, stats, list(sinks)
        self.logged = 0  # timesteps of the latest point

    def _on_training_start(self) -> None:
        super()._on_training_start()
        self.logged = self.num_timesteps
        self.next_log = self.num_timesteps + self.log_every

    def _on_step(self) -> bool:
        evaluation = self.evaluation.latest if self.evaluation is not None else {}
        if self.num_timesteps >= self.next_log or evaluation:
            self.log_point(evaluation)
            while self.next_log <= self.num_timesteps:
                self.next_log += self.log_every
        return True

    def _on_training_end(self) -> None:
        if self.num_timesteps > self.logged:  # the curves end where training ended
            self.log_point()

    def log_point(self, evaluation: dict | None = None) -> dict:
        """Aggregate the episodes since the last point, add losses and extra stats, write and send them."""
        eps = self.tally.take_window()
        m: dict[str, float] = {"fps": self.rate(), "episodes": float(self.tally.episodes), **(evaluation or {})}
        if self.stats is not None:
            m.update({k: float(v) for k, v in self.stats().items() if math.isfinite(v)})
        if eps:
            m.update(
                {
                    "episode/return": float(np.mean([e["return"] for e in eps])),
                    "episode/success_rate": float(np.mean([e["success"] for e in eps])),
                    "episode/subtasks": float(np.mean([e["subtasks"] for e in eps])),
                    "episode/time": float(np.mean([e["time"] for e in eps])),
                }
            )
            feats = np.mean([e["features"] for e in eps], axis=0)
            m.update({f"features/{n}": float(v) for n, v in zip(self.tally.names, feats)})
        for key, value in self.model.logger.name_to_value.items():
            if key.startswith("train/") and isinstance(value, (int, float)) and math.isfinite(value):
                m[f"loss/{key[6:]}"] = float(value)
        self.logged = int(self.num_timesteps)
        check_space(self.run / "metrics.jsonl", 0)
        append_line(self.run / "metrics.jsonl", json.dumps({"timesteps": int(self.num_timesteps), **m}))
        for sink in self.sinks:
            sink(int(self.num_timesteps), m)
        return m


class Checkpoints(BaseCallback):
    """Every `every` timesteps a checkpoint (model, env statistics, `parts`), keeping the newest `keep`."""

    def __init__(
        self,
        *,
        run: Path,
        every: int,
        keep: int = 3,
        tally: EpisodeTally,
        parts: dict | None = None,
        before_save: Callable[[], None] | None = None,
    ):
        super().__init__()
        self.run, self.every, self.keep, self.tally = run, every, keep, tally
        self.parts, self.before_save = parts or {}, before_save

    def _on_training_start(self) -> None:
        self.next_ckpt = self.num_timesteps + self.every

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.next_ckpt:
            self.checkpoint()
            self.next_ckpt += self.every
        return True

    def checkpoint(self) -> Path:
        """Save a checkpoint (if the disk has room for it and the reserve) and keep only the newest few."""
        newest = sorted((self.run / "checkpoints").glob("[0-9]*"))
        target = self.run / "checkpoints" / f"{self.num_timesteps:010d}"
        check_space(target, tree_bytes(newest[-1]) if newest else 0)
        if self.before_save is not None:  # e.g. the recording flushed: it holds all logged up to the checkpoint
            self.before_save()
        with deferred():  # a Ctrl-C mid-write (torch.save turns it into a RuntimeError) stops after the save
            path = save_checkpoint(target, self.model, self.training_env, {"episodes": self.tally.episodes}, self.parts)
            for p in sorted((self.run / "checkpoints").glob("[0-9]*"))[: -self.keep]:
                shutil.rmtree(p, ignore_errors=True)
        return path


class StopAtSubtasks(BaseCallback):
    """Stop training once an evaluation's subtask share reaches `at`, not before `after` timesteps."""

    def __init__(self, *, evaluation: PeriodicEvaluation, at: float, after: int = 0):
        super().__init__()
        self.evaluation, self.at, self.after = evaluation, at, after
        self.stopped_early = False

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.after and self.evaluation.latest.get("eval/subtasks", 0.0) >= self.at:
            self.stopped_early = True
        return not self.stopped_early


class TrainingMonitor(CallbackList):
    """The training callbacks in their order of a step, and what a run reads back from them."""

    def __init__(self, callbacks: list[BaseCallback]):
        super().__init__(callbacks)

    def _first(self, kind: type):
        return next((c for c in self.callbacks if isinstance(c, kind)), None)

    @property
    def episodes(self) -> int:
        """Episodes finished, this session and before it."""
        return self._first(EpisodeTally).episodes

    @property
    def stopped_early(self) -> bool:
        """Whether an evaluation's subtask share stopped training."""
        stop = self._first(StopAtSubtasks)
        return stop is not None and stop.stopped_early

    def stop_progress(self) -> None:
        """Take the progress bar off the terminal (training stopped by a signal or a full disk)."""
        bar = self._first(ProgressBar)
        if bar is not None:
            bar.stop()
