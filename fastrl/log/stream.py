"""A Rerun recording stream that saves to a file, on fastrl's own timelines only."""

from __future__ import annotations

from pathlib import Path

import rerun as rr


def saved_stream(path: Path, recording_id: str | None = None, app_id: str = "fastrl") -> rr.RecordingStream:
    """A stream writing to `path`, without Rerun's log time (steps, sim_time and timesteps are the timelines)."""
    rec = rr.RecordingStream(app_id, recording_id=recording_id)
    rec.set_log_time_enabled(False)
    rec.save(path)
    return rec
