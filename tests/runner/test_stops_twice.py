"""Ctrl-C twice in quick succession (the second while the first stop saves): no traceback at exit; the run resumes."""

from __future__ import annotations

import json
import signal
import time

import pytest

from .test_stops import EXTRA, STAGES, resume, sets, start, status, the_run, verify, wait_until

pytestmark = [pytest.mark.timeout(300), pytest.mark.slow]


@pytest.mark.parametrize("stage", ["training", "evaluation"])
def test_a_second_sigint_50_ms_after_the_first_is_ignored_until_exit(tmp_path, stage):
    """Two SIGINTs 50 ms apart to a real `fastrl run`: one stop, saved, exit 130, nothing from interpreter shutdown."""
    runs = tmp_path / "runs"
    proc = start([*STAGES[stage], "--runs", str(runs), *sets(EXTRA[stage])], tmp_path)
    run = wait_until(lambda: the_run(runs), proc)
    if stage == "training":  # at once: the stop then comes as periodic checkpoints are written, the likeliest to race
        wait_until(lambda: list(run.glob("checkpoints/[0-9]*/state.json")), proc)
    else:
        wait_until(lambda: status(run) == "evaluating", proc)
    proc.send_signal(signal.SIGINT)
    time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "Exception ignored" not in err and "KeyboardInterrupt" not in err, err
    assert err.splitlines()[-1] == f"resume with: fastrl run --resume {run}", err
    verify(run / "recording.rrd")
    meta = json.loads((run / "meta.json").read_text())
    # at evaluation's very start the stop may land between stages, before its episodes: then a plain interruption
    assert meta["status"] in ("interrupted", "trained, evaluation interrupted" if stage == "evaluation" else "")
    assert resume(run, 256 if stage == "training" else None) >= meta["trained_timesteps"]
