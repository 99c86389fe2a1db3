"""Training callback: episode statistics, curves to Rerun and metrics.jsonl, checkpoints, progress bar."""

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
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize

from ..agents.sb3 import save_checkpoint
from ..atomic import append_line
from .stops import check_space, tree_bytes


class TrainingMonitor(BaseCallback):
    """Collects per-episode figures from env infos and logs them every `log_every` timesteps.

    Optionally it adds `stats()` (e.g. the discriminator's) to every point, saves `parts` (objects with
    state_dict) in checkpoints, and every `eval_every` steps runs `evaluator()`, stopping training when the
    evaluation's subtask share reaches `stop_at`.
    """

    def __init__(
        self,
        run: Path,
        feature_names: list[str],
        *,
        total: int,
        log_every: int,
        checkpoint_every: int,
        recorder=None,
        progress: bool = True,
        keep_checkpoints: int = 3,
        stats: Callable[[], dict] | None = None,
        parts: dict | None = None,
        evaluator: Callable[[], dict] | None = None,
        eval_every: int = 0,
        stop_at: float | None = None,
    ):
        super().__init__()
        self.run, self.names, self.total = run, feature_names, total
        self.log_every, self.checkpoint_every, self.keep = log_every, checkpoint_every, keep_checkpoints
        self.stats, self.parts = stats, parts or {}
        self.evaluator, self.eval_every, self.stop_at = evaluator, eval_every, stop_at
        self.next_eval = 0
        self.stopped_early = False
        self.recorder = recorder
        self.recent = deque(maxlen=100)
        self.window: list[dict] = []
        self.episodes = 0
        self.next_log = self.next_ckpt = self.next_tick = 0
        self.logged = 0  # timesteps of the latest point
        self.started = time.perf_counter()
        self.start_steps = 0
        self.progress = Progress(
            TextColumn("[bold]{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[rate]:>6} steps/s"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            TextColumn("{task.fields[status]}"),
            disable=not progress,
        )
        self.task_id = None

    def _on_training_start(self) -> None:
        n = self.training_env.num_envs
        self.ret, self.feats = np.zeros(n), np.zeros((n, len(self.names)))
        self.pick = itemgetter(*self.names) if len(self.names) > 1 else lambda f: (f[self.names[0]],)
        self.start_steps = self.logged = self.num_timesteps
        self.started = time.perf_counter()
        self.next_log = self.num_timesteps + self.log_every
        self.next_ckpt = self.num_timesteps + self.checkpoint_every
        self.next_eval = self.num_timesteps + self.eval_every
        self.progress.start()
        self.task_id = self.progress.add_task(
            "training", total=self.total, completed=self.num_timesteps, rate="-", status=""
        )

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
        if self.num_timesteps >= self.next_tick:
            self.next_tick += 2048
            self.progress.update(self.task_id, completed=self.num_timesteps, rate=f"{self.rate():.0f}")
        evaluation = {}
        if self.evaluator is not None and self.eval_every and self.num_timesteps >= self.next_eval:
            self.progress.update(self.task_id, status="evaluating")
            evaluation = self.evaluator()
            self.next_eval += self.eval_every
        if self.num_timesteps >= self.next_log or evaluation:
            self.log_point(evaluation)
            while self.next_log <= self.num_timesteps:
                self.next_log += self.log_every
        if self.num_timesteps >= self.next_ckpt:
            self.checkpoint()
            self.next_ckpt += self.checkpoint_every
        if self.stop_at is not None and evaluation.get("eval/subtasks", 0.0) >= self.stop_at:
            self.stopped_early = True
            return False
        return True

    def _on_training_end(self) -> None:
        if self.num_timesteps > self.logged:  # the curves end where training ended
            self.log_point()
        self.progress.stop()

    def rate(self) -> float:
        """Training steps per second in this session."""
        return (self.num_timesteps - self.start_steps) / max(1e-9, time.perf_counter() - self.started)

    def log_point(self, evaluation: dict | None = None) -> dict:
        """Aggregate the episodes since the last point, add losses and extra stats, write and send them."""
        eps = self.window or list(self.recent)[-10:]
        m: dict[str, float] = {"fps": self.rate(), "episodes": float(self.episodes), **(evaluation or {})}
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
            m.update({f"features/{n}": float(v) for n, v in zip(self.names, feats)})
        for key, value in self.model.logger.name_to_value.items():
            if key.startswith("train/") and isinstance(value, (int, float)) and math.isfinite(value):
                m[f"loss/{key[6:]}"] = float(value)
        self.window = []
        self.logged = int(self.num_timesteps)
        check_space(self.run / "metrics.jsonl", 0)
        append_line(self.run / "metrics.jsonl", json.dumps({"timesteps": int(self.num_timesteps), **m}))
        if self.recorder is not None:
            self.recorder.log_training(int(self.num_timesteps), m)
        status = f"success {m['episode/success_rate']:.0%}  subtasks {m['episode/subtasks']:.0%}" if eps else ""
        self.progress.update(self.task_id, completed=self.num_timesteps, rate=f"{m['fps']:.0f}", status=status)
        return m

    def checkpoint(self) -> Path:
        """Save a checkpoint (if the disk has room for it and the reserve) and keep only the newest few."""
        newest = sorted((self.run / "checkpoints").glob("[0-9]*"))
        target = self.run / "checkpoints" / f"{self.num_timesteps:010d}"
        check_space(target, tree_bytes(newest[-1]) if newest else 0)
        if self.recorder is not None:  # before the checkpoint exists, the recording holds all logged up to it
            self.recorder.flush()
        path = save_checkpoint(
            target,
            self.model,
            self.training_env,
            {"episodes": self.episodes},
            self.parts,
        )
        old = sorted((self.run / "checkpoints").glob("[0-9]*"))[: -self.keep]
        for p in old:
            shutil.rmtree(p, ignore_errors=True)
        return path
