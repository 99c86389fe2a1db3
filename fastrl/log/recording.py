"""RunRecorder: the one Rerun recording of a run, streamed to an .rrd file."""

from __future__ import annotations

import uuid
from pathlib import Path
from typing import Self

import numpy as np
import rerun as rr

from ..data.episode import EpisodeRecord
from ..model.compiler import CompiledTask
from .episode import log_episode
from .layout import episode_name, run_blueprint
from .metrics import TrainingCurves, summary_markdown
from .scene import default_eye, log_scene

FLUSH_TICK_S = 5.0


class RunRecorder:
    """Owns one RecordingStream that streams scene, episodes, curves and summary to `path`."""

    def __init__(
        self,
        path: str | Path,
        app_id: str = "fastrl",
        recording_id: str | None = None,
        run_name: str = "",
    ):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # The SDK's default recording id is shared by the whole process: make each run distinct.
        self.recording_id = recording_id or str(uuid.uuid4())
        # Training rows arrive seconds apart: a long batcher tick merges them into few chunks
        # (a row sent on its own costs ~1 kB of chunk metadata in the file). close() flushes.
        self.rec = rr.RecordingStream(
            app_id,
            recording_id=self.recording_id,
            batcher_config=rr.ChunkBatcherConfig(flush_tick=FLUSH_TICK_S),
        )
        self.rec.set_log_time_enabled(False)  # only our timelines: step, sim_time, timesteps
        self.rec.save(self.path)
        if run_name:
            self.rec.send_recording_name(run_name)
        self.curves = TrainingCurves(self.rec)
        self.closed = False
        self.eye: tuple | None = None

    def log_scene(self, task: CompiledTask) -> None:
        """Static scene under world/scene and Z-up view coordinates on world."""
        log_scene(self.rec, task, root="world")
        self.eye = default_eye(task)

    def log_episode(
        self,
        index: int,
        ep: EpisodeRecord,
        task: CompiledTask,
        fov_deg: float,
        image_size: tuple[int, int] | None = None,
    ) -> None:
        """The whole episode as columns under world/eval/ep_XX and metrics/eval/ep_XX."""
        name = episode_name(index)
        log_episode(
            self.rec,
            ep,
            task,
            fov_deg,
            image_size,
            world=f"world/eval/{name}",
            metrics=f"metrics/eval/{name}",
            timesteps=self.curves.last,
        )

    def log_training(self, timesteps: int, metrics: dict[str, float]) -> None:
        """One row of training metrics at `timesteps` (metrics/train/<name>); NaN/None skipped."""
        self.curves.row(timesteps, metrics)

    def log_training_columns(self, timesteps: np.ndarray, metrics: dict[str, np.ndarray]) -> None:
        """Many rows of training metrics at once (e.g. a resumed run's history)."""
        self.curves.columns(timesteps, metrics)

    def log_summary(self, summary: dict) -> None:
        """The evaluation's headline figures as a static markdown document at `summary`."""
        self.rec.log(
            "summary",
            rr.TextDocument(summary_markdown(summary), media_type=rr.MediaType.MARKDOWN),
            static=True,
        )

    def send_blueprint(self, n_episodes: int, irl: bool = False, curves: bool = True) -> None:
        """Send the layout the viewer opens with (scene + episode 0, image, curves, summary)."""
        blueprint = run_blueprint(n_episodes, eye=self.eye, irl=irl, curves=curves)
        self.rec.send_blueprint(blueprint, make_active=True, make_default=True)

    def close(self) -> None:
        """Flush everything and close the file (idempotent)."""
        if self.closed:
            return
        self.closed = True
        try:
            self.rec.flush(timeout_sec=30.0)
        finally:
            self.rec.disconnect()

    def __enter__(self) -> Self:
        """Use as `with RunRecorder(path) as rec:`; closes on exit."""
        return self

    def __exit__(self, *exc) -> None:
        """Close the recording."""
        self.close()
