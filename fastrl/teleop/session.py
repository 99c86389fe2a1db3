"""One recorded attempt: the live env stepped in real time by held keys, saved as it goes."""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..assist import Suggester, Suggestion, ValueCue
from ..data.replay import cue_events
from ..env.fast_env import FastEnv
from ..spec import spec_hash, task_hash
from ..spec.models import TaskSpec
from .keymap import BY_CODE, driven_action
from .writer import AttemptWriter


@dataclass
class Assistance:
    """What --assist brings: a suggester (trained policy) and the value cue; either may be missing."""

    suggester: Suggester | None = None
    cue: ValueCue = field(default_factory=ValueCue)
    run: str | None = None
    suggest_every: int | None = None  # control steps between path suggestions nobody asked for (None: only on request)


class Session:
    """Steps the task at the control rate with the action of the key held last; never blocks on the viewer."""

    def __init__(
        self,
        spec: TaskSpec,
        subject: str,
        path: Path,
        *,
        seed: int = 0,
        assist: Assistance | None = None,
        hold_s: float = 0.15,
        image_size: int = 128,
        spec_source: str | None = None,
    ):
        if spec.actions.mode != "discrete":
            raise ValueError(
                "recording drives the scope with discrete increments: use a spec with actions.mode: "
                "discrete (or --set actions.mode=discrete)"
            )
        self.spec, self.seed, self.hold = spec, seed, hold_s
        self.env = FastEnv(spec, width=image_size, height=image_size)
        self.assist = assist or Assistance()
        self.keys: deque = deque()
        self.lock = threading.Lock()
        self.held, self.held_until = 0, 0.0
        self.driven, self.sizes = 0, [len(t.qadr) for t in self.env.task.instruments]
        self.stop: str | None = None
        self.want_suggestion = False
        self.suggestion: Suggestion | None = None
        self.suggestions: list[dict] = []
        self.cue_trace: list[list] = []
        self.infos: list[dict] = []
        meta = {
            "spec": spec.name,
            "spec_hash": spec_hash(spec),
            "task_hash": task_hash(spec),
            "subject": subject,
            "source": "human",
            "seed": seed,
            "skill": None,
            "control_hz": spec.episode.control_hz,
            "recorded_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "complete": False,
        }
        if spec_source:
            meta["spec_source"] = spec_source
        if self.assist.run:
            meta["assist_run"] = self.assist.run
        self.writer = AttemptWriter(path, meta)
        self.periods, self.work, self.skipped_frames, self.pulled_ticks = [], [], 0, 0

    # ---- input (called from the viewer's thread) -------------------------------------------
    def on_key(self, code: int) -> None:
        """Queue a key press (GLFW code); unknown keys are ignored."""
        if code in BY_CODE:
            with self.lock:
                self.keys.append((time.monotonic(), code))

    def _tools(self):
        """The instruments' coordinates, or None without instruments."""
        return self.env.instrument_coordinates() if self.sizes else None

    # ---- the loop --------------------------------------------------------------------------
    def start(self) -> dict:
        """Reset the task and record the first sample."""
        _, info = self.env.reset(seed=self.seed)
        self.info = info
        self.infos.append(info)
        self.writer.add(0.0, self.env.portal_coordinates(), None, self._tools(), self.env.body_poses())
        self._cue()
        return info

    def tick(self, now: float | None = None, pulled: bool = False) -> dict:
        """Apply queued keys, step once, record, and compute what assistance was asked for.

        `pulled`: the mouse is pulling the scope (viewer perturbation); the servos then follow it.
        """
        now = time.monotonic() if now is None else now
        with self.lock:
            pending, self.keys = list(self.keys), deque()
        for _, code in pending:
            key = BY_CODE[code]
            if key.command == "quit":
                self.stop = self.stop or "quit"
            elif key.command == "suggest":
                self.want_suggestion = True
            elif key.command == "switch":
                self.driven, self.held = (self.driven + 1) % (1 + len(self.sizes)), 0
            else:
                self.held, self.held_until = driven_action(key.action, self.driven, self.sizes), now + self.hold
        action = self.held if now < self.held_until else 0
        _, _, term, trunc, info = self.env.step(action)
        if pulled:
            self.env.hold_here()
            self.pulled_ticks += 1
        self.info = info
        self.infos.append(info)
        self.writer.add(info["time"], self.env.portal_coordinates(), action, self._tools(), self.env.body_poses())
        self._cue()
        every = self.assist.suggest_every
        if every and self.env.steps % every == 0:
            self.want_suggestion = True
        if self.want_suggestion and self.assist.suggester is not None:
            self.suggest()
        self.want_suggestion = False
        if term or trunc:
            self.stop = self.stop or ("success" if info["success"] else "time limit")
        return info

    def suggest(self) -> Suggestion:
        """A path suggestion from the current state (kept for the recording)."""
        s = self.assist.suggester.suggest(self.env)
        self.suggestion = s
        self.suggestions.append({"step": self.env.steps, "reached": s.reached, "ms": round(s.ms, 2)})
        return s

    def _cue(self) -> None:
        """The colour cue of the current state, logged with the step."""
        cue = self.assist.cue
        raw = cue.raw(self.env)
        self.cue_level = cue.level(raw)
        self.cue_trace.append([self.env.steps, raw, self.cue_level])

    def run(self, display=None, max_seconds: float | None = None) -> str:
        """Tick in real time until the task ends, quit, the window closes, or `stop` is set (by a signal)."""
        dt = 1.0 / self.spec.episode.control_hz
        if not self.infos:
            self.start()
        t_next = time.monotonic()
        last, show_s, skipped = None, 0.0, 0
        while self.stop is None:
            t0 = time.monotonic()
            if last is not None:
                self.periods.append(t0 - last)
            last = t0
            if display is not None:
                with display.lock():
                    self.tick(t0, display.pulling())
                # draw only if it fits before the next tick (the control rate comes first), at least every 5th tick
                if t_next + dt - time.monotonic() > show_s or skipped >= 4:
                    t1 = time.monotonic()
                    if not display.show(self):
                        self.stop = self.stop or "window closed"
                    show_s, skipped = 0.8 * show_s + 0.2 * (time.monotonic() - t1), 0
                else:
                    skipped += 1
                    self.skipped_frames += 1
                    if not display.running():
                        self.stop = self.stop or "window closed"
            else:
                self.tick(t0)
            self.work.append(time.monotonic() - t0)
            if max_seconds is not None and self.env.steps * dt >= max_seconds:
                self.stop = self.stop or "time limit"
            t_next += dt
            time.sleep(max(0.0, t_next - time.monotonic()))
            if time.monotonic() - t_next > 5 * dt:  # fell far behind (a stall): do not try to catch up
                t_next = time.monotonic()
        return self.stop

    def finish(self, **meta) -> Path | None:
        """Save the complete attempt with why it ended, its cue events and timing."""
        return self.writer.flush(
            complete=True,
            end=self.stop,
            events=cue_events(self.infos),
            realtime=self.timing(),
            suggestions=self.suggestions,
            mouse_ticks=self.pulled_ticks,
            cue={"kind": self.assist.cue.kind, "lo": self.assist.cue.lo, "hi": self.assist.cue.hi},
            **meta,
        )

    def timing(self) -> dict:
        """Real-time figures of the loop (ms)."""
        p, w = np.array(self.periods) * 1000, np.array(self.work) * 1000
        dt = 1000.0 / self.spec.episode.control_hz
        if not len(p):
            return {"control_period_ms": dt}
        return {
            "control_period_ms": dt,
            "ticks": len(p) + 1,
            "period_ms_mean": float(p.mean()),
            "period_ms_p95": float(np.percentile(p, 95)),
            "period_ms_max": float(p.max()),
            "work_ms_mean": float(w.mean()),
            "work_ms_p95": float(np.percentile(w, 95)),
            "late_ticks": int((p > 1.5 * dt).sum()),
            "display_frames_skipped": self.skipped_frames,
        }
