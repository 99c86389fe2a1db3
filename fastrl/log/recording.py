"""RunRecorder: the one Rerun recording of a run, streamed to an .rrd file; repair of a torn one."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import uuid
from pathlib import Path
from typing import Self

# A file sink that hits a full disk logs raw Rust lines to stderr; the runner reports that itself, in a sentence.
# (Set before rerun is first imported; a RUST_LOG of the user's own wins.)
os.environ.setdefault("RUST_LOG", "warn,re_log_encoding::rrd=off,re_sdk::recording_stream=off")

import numpy as np  # noqa: E402
import rerun as rr  # noqa: E402

from ..atomic import DiskFull, free_bytes  # noqa: E402
from ..data.episode import EpisodeRecord  # noqa: E402
from ..model.compiler import CompiledTask  # noqa: E402
from .episode import log_episode  # noqa: E402
from .layout import episode_name, run_blueprint  # noqa: E402
from .metrics import TrainingCurves, summary_markdown  # noqa: E402
from .scene import default_eye, log_scene  # noqa: E402

FLUSH_TICK_S = 5.0
DISCONNECT_WAIT_S = 10.0  # a healthy close takes well under this; then the disk is checked
FULL_DISK_BYTES = 1 << 20  # less free than this: a sink still writing after DISCONNECT_WAIT_S is stuck


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
        self.warm = TrainingCurves(self.rec, root="metrics/warm_start")
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

    def log_warm_start(self, steps: int, metrics: dict[str, float]) -> None:
        """One round of a warm start (metrics/warm_start/<name>) at the labelled steps so far."""
        self.warm.row(steps, metrics)

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

    def send_blueprint(
        self, n_episodes: int, irl: bool = False, curves: bool = True, pixels: bool = False, warm: bool = False
    ) -> None:
        """Send the layout the viewer opens with (scene + episode 0, image, the policy's frames, curves (the warm
        start's rounds), summary)."""
        blueprint = run_blueprint(n_episodes, eye=self.eye, irl=irl, curves=curves, pixels=pixels, warm=warm)
        self.rec.send_blueprint(blueprint, make_active=True, make_default=True)

    def flush(self) -> None:
        """Write everything logged so far to the file; DiskFull if the file could not be written."""
        try:
            self.rec.flush(timeout_sec=30.0)
        except RuntimeError as e:  # the file writer died (on this SDK: only for want of space or a vanished disk)
            raise DiskFull(self.path, None, free_bytes(self.path)) from e

    def close(self) -> None:
        """Flush everything and close the file (idempotent); DiskFull if it could not be written whole."""
        if self.closed:
            return
        self.closed = True
        try:
            self.flush()
        finally:
            self._disconnect()

    def _disconnect(self) -> None:
        """Close the file sink; on a full disk, give up on a sink stuck writing (the file stays valid up to its last
        complete chunk) instead of waiting for ever, and skip Rerun's at-exit flush, which would wait on it too."""
        closing = threading.Thread(target=self.rec.disconnect, daemon=True)
        closing.start()
        closing.join(DISCONNECT_WAIT_S)
        while closing.is_alive():
            free = free_bytes(self.path)
            if free is not None and free < FULL_DISK_BYTES:
                rr.unregister_shutdown()
                return
            closing.join(DISCONNECT_WAIT_S)

    def __enter__(self) -> Self:
        """Use as `with RunRecorder(path) as rec:`; closes on exit."""
        return self

    def __exit__(self, *exc) -> None:
        """Close the recording."""
        self.close()


def rerun_cli(*args: str, timeout: float = 300.0) -> subprocess.CompletedProcess:
    """Run the `rerun` command line of the installed SDK (quietly, output captured)."""
    env = {**os.environ, "CI": "1", "RUST_LOG": "error"}
    return subprocess.run(
        [sys.executable, "-m", "rerun", *args], capture_output=True, text=True, timeout=timeout, env=env
    )


def recording_problem(path: Path) -> str | None:
    """Why `rerun rrd verify` rejects a recording (e.g. cut short by a kill or a full disk), or None if it is valid."""
    res = rerun_cli("rrd", "verify", str(path))
    if res.returncode == 0:
        return None
    lines = [line.strip() for line in (res.stderr + res.stdout).splitlines() if line.strip()]
    return lines[0] if lines else f"rerun rrd verify exited with {res.returncode}"


def repair_recording(path: Path) -> bool:
    """Rewrite a torn recording in place from its complete chunks; False if it was valid (ValueError: unreadable)."""
    path = Path(path)
    if recording_problem(path) is None:
        return False
    tmp = path.with_name(f".{path.name}.repair-{os.getpid()}.rrd")
    res = rerun_cli("rrd", "merge", "--continue-on-error", str(path), "-o", str(tmp))
    if res.returncode != 0 or not tmp.exists() or recording_problem(tmp) is not None:
        tmp.unlink(missing_ok=True)
        if "No space left" in res.stderr:
            raise DiskFull(tmp, path.stat().st_size)
        raise ValueError(f"{path}: no complete chunk could be read back ({res.stderr.strip()[-200:]})")
    os.replace(tmp, path)
    return True
