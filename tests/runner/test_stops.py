"""Every stop recoverable: SIGINT, SIGTERM and SIGKILL in training, IRL and evaluation; torn checkpoints; full disk."""

import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from rerun.chunk import RrdReader
from typer.testing import CliRunner

from fastrl.agents.sb3 import checkpoint_problem
from fastrl.atomic import DiskFull, atomic_write, write_json
from fastrl.cli import app
from fastrl.forked import deferred
from fastrl.log.recording import recording_problem
from fastrl.runner.runs.rundir import latest_checkpoint
from fastrl.runner.runs.stops import stop_on_sigterm

from ..conftest import spec_file

pytestmark = pytest.mark.slow  # trains or drives a viewer end to end

TINY = [
    "train.n_envs=2",
    "train.ppo.n_steps=64",
    "train.ppo.batch_size=64",
    "train.ppo.n_epochs=1",
    "train.log_every=128",
    "train.checkpoint_every=256",
    "evaluate.episodes=2",
    "evaluate.record_episodes=1",
    "evaluate.image_every=10",
    "episode.time_limit=8",
]
IRL = [  # GAIL and AIRL on PPO learn with irl.generator's envs and hyperparameters
    "irl.demonstrations.expert=2",
    "evaluate.image_every=0",
    "irl.generator.n_envs=2",
    "irl.generator.ppo.n_steps=64",
    "irl.generator.ppo.batch_size=64",
    "irl.generator.ppo.n_epochs=1",
]
LONG_EVAL = ["evaluate.episodes=4", "evaluate.record_episodes=4", "evaluate.image_every=1"]  # seconds: time to stop in
SPEC = str(spec_file("tracelines"))
STAGES = {
    "training": ["run", SPEC, "--timesteps", "100000"],
    "irl": ["irl", SPEC, "--algorithm", "gail", "--timesteps", "100000"],
    "evaluation": ["run", SPEC, "--timesteps", "256"],
}
EXTRA = {"training": [], "irl": IRL, "evaluation": LONG_EVAL}


def sets(extra=()) -> list[str]:
    """CLI --set arguments for the tiny budget."""
    return [a for kv in [*TINY, *extra] for a in ("--set", kv)]


def start(args: list[str], cwd: Path, quiet: bool = True) -> subprocess.Popen:
    """The real command line in a subprocess (SIGINT at its default, as in a terminal; no progress bar if quiet)."""
    return subprocess.Popen(
        [sys.executable, "-m", "fastrl.cli", *args, *(["--no-progress"] if quiet else [])],
        cwd=cwd,
        env={**os.environ, "CI": "1", "MUJOCO_GL": "egl", "PYTHONFAULTHANDLER": "1"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )


def verify(*paths: Path) -> None:
    """`rerun rrd verify` accepts every one of the recordings (one call for all)."""
    res = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", *map(str, paths)],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "CI": "1"},
    )
    assert res.returncode == 0, res.stderr
    assert f"{len(paths)} file{'s' if len(paths) > 1 else ''} verified without error" in res.stdout + res.stderr


def wait_until(ready, proc: subprocess.Popen, timeout: float = 90.0):
    """Poll `ready()` until it returns something truthy, failing if the process ends first."""
    t0 = time.time()
    while not (found := ready()):
        assert proc.poll() is None, proc.communicate()
        assert time.time() - t0 < timeout, "the stage was not reached"
        time.sleep(0.05)
    return found


def status(run: Path) -> str:
    """meta.json's status (empty while it is being written)."""
    try:
        return json.loads((run / "meta.json").read_text()).get("status", "")
    except (OSError, ValueError):
        return ""


def the_run(runs: Path) -> Path | None:
    """The single run directory under runs, once it exists."""
    found = list(runs.glob("*/*/spec.yaml"))
    return found[0].parent if found else None


def reach(stage: str, runs: Path, proc: subprocess.Popen) -> Path:
    """Wait until the run is in `stage` (training or IRL with a checkpoint written, or evaluating)."""
    run = wait_until(lambda: the_run(runs), proc)
    if stage == "evaluation":
        wait_until(lambda: status(run) == "evaluating", proc)
        time.sleep(0.5)  # an episode or two streamed into the recording
    else:
        wait_until(lambda: list(run.glob("checkpoints/[0-9]*/state.json")), proc)
        time.sleep(0.3)
    return run


def curve_timesteps(rrd: Path) -> list[int]:
    """Every `timesteps` value of the training curves in a recording."""
    values = []
    for chunk in RrdReader(str(rrd)).stream():
        if "timesteps" in chunk.timeline_names:
            values += chunk.to_record_batch().column("timesteps").to_pylist()
    return values


def checkpoint_timesteps(run: Path) -> int:
    """Timesteps of the newest whole checkpoint."""
    return json.loads((latest_checkpoint(run) / "state.json").read_text())["timesteps"]


def resume(run: Path, more: int | None = 256) -> int:
    """`fastrl run --resume` in-process (with `more` timesteps beyond the newest checkpoint); its final timesteps."""
    extra = ["--timesteps", str(checkpoint_timesteps(run) + more)] if more else []
    res = CliRunner().invoke(app, ["run", "--resume", str(run), *extra, "--no-progress"])
    assert res.exit_code == 0, res.output
    assert (run / "eval.json").exists() and status(run) == "done"
    return json.loads((run / "final" / "state.json").read_text())["timesteps"]


def newer_checkpoint(run: Path, than: int):
    """A checkpoint past `than` timesteps, once one is written."""
    return [p for p in run.glob("checkpoints/[0-9]*/state.json") if int(p.parent.name) > than]


def stop_with(sig: signal.Signals, proc: subprocess.Popen, run: Path, stage: str) -> dict:
    """Send SIGINT or SIGTERM and check the stop: exit 128+n, no traceback, checkpoint, valid recording, last line."""
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + sig, err
    assert "Traceback" not in err and err.splitlines()[-1] == f"resume with: fastrl run --resume {run}", err
    assert err.startswith(f"{sig.name}: "), err
    verify(run / "recording.rrd")
    meta = json.loads((run / "meta.json").read_text())
    if stage == "evaluation":
        assert meta["status"] == "trained, evaluation interrupted" and checkpoint_problem(run / "final") is None
    else:
        assert meta["status"] == "interrupted"
        assert checkpoint_timesteps(run) == meta["trained_timesteps"] > 0  # saved at the very step it stopped
    return meta


@pytest.mark.parametrize("stage", ["training", "irl", "evaluation"])
def test_sigint_sigterm_and_sigkill_each_leave_a_resumable_run_and_a_valid_recording(tmp_path, stage):
    """One run stopped three times in the same stage (SIGINT, SIGTERM, then SIGKILL), resumed after each."""
    runs = tmp_path / "runs"
    proc = start([*STAGES[stage], "--runs", str(runs), *sets(EXTRA[stage])], tmp_path)
    run = reach(stage, runs, proc)
    reached = 0
    for k, sig in enumerate([signal.SIGINT, signal.SIGTERM]):
        reached = stop_with(sig, proc, run, stage)["trained_timesteps"]
        more = [] if stage == "evaluation" else ["--timesteps", "100000"]
        proc = start(["run", "--resume", str(run), *more], tmp_path)
        if stage == "evaluation":
            wait_until(lambda: status(run) == "evaluating", proc)
            time.sleep(0.5)
        else:  # trains on from the checkpoint: a new one, then one more so there is data past it for the kill
            wait_until(lambda done=reached: newer_checkpoint(run, done), proc)
        assert (run / f"recording.part{k + 1}.rrd").exists()
    if stage != "evaluation":
        wait_until(lambda: len(newer_checkpoint(run, reached)) >= 2, proc)
    proc.kill()
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    kept = checkpoint_timesteps(run)
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines() if line.endswith("}")]
    before = [r for r in rows if r["timesteps"] <= kept]
    assert before and before[-1]["timesteps"] > (0 if stage == "evaluation" else reached)
    assert "footer" in recording_problem(run / "recording.rrd")  # the kill left it without its end
    if stage == "evaluation":  # the documented repair step (elsewhere, --resume repairs it by itself)
        res = CliRunner().invoke(app, ["repair", str(run)])
        assert res.exit_code == 0 and f"repaired  {run / 'recording.rrd'}" in res.output, res.output
        verify(run / "recording.rrd")

    final = resume(run, None if stage == "evaluation" else 256)
    assert final >= kept
    killed = run / "recording.part3.rrd"
    verify(*(run / f"recording{part}.rrd" for part in ("", ".part1", ".part2", ".part3")))
    # what was logged up to the checkpoint the kill fell back to is kept: in the old recording and in metrics.jsonl
    assert max(curve_timesteps(killed)) >= kept
    after = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert after[: len(before)] == before
    assert [r["timesteps"] for r in after] == sorted(r["timesteps"] for r in after)


KILL_LOOP = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    from fastrl.agents.sb3 import build_model, make_vec_env, save_checkpoint
    from fastrl.spec import load_spec
    spec = load_spec(sys.argv[1], ["train.n_envs=1", "train.ppo.n_steps=64", "train.ppo.batch_size=64"])
    venv = make_vec_env(spec, 1, 0)
    model = build_model(spec, venv)
    root = Path(sys.argv[2])
    print("ready", flush=True)
    for k in range(1, 100000):
        model.num_timesteps = k
        save_checkpoint(root / f"{k:010d}", model, venv, {"episodes": k})
        save_checkpoint(root / f"{k:010d}", model, venv, {"episodes": k})  # the same name again: a swap
    """
)


def test_a_kill_at_any_moment_leaves_a_whole_checkpoint_to_resume_from(tmp_path):
    script = tmp_path / "loop.py"
    script.write_text(KILL_LOOP)
    for delay in (0.2, 0.9):
        root = tmp_path / f"run{delay}" / "checkpoints"
        proc = subprocess.Popen(
            [sys.executable, str(script), SPEC, str(root)], stdout=subprocess.PIPE, text=True, env=dict(os.environ)
        )
        assert proc.stdout.readline().strip() == "ready"
        wait_until(lambda root=root: len(list(root.glob("[0-9]*"))) >= 2, proc)
        time.sleep(delay)
        proc.kill()
        proc.communicate(timeout=30)
        newest = latest_checkpoint(root.parent)
        assert newest is not None and checkpoint_problem(newest) is None
        assert json.loads((newest / "state.json").read_text())["timesteps"] >= 2


def test_a_damaged_newest_checkpoint_is_reported_and_resume_falls_back(tmp_path):
    res = CliRunner().invoke(
        app, ["run", SPEC, "--timesteps", "768", "--runs", str(tmp_path), "--no-progress", *sets()]
    )
    assert res.exit_code == 0, res.output
    run = the_run(tmp_path)
    newest = latest_checkpoint(run)
    older = sorted(run.glob("checkpoints/[0-9]*"))[-2]
    weights = newest / "weights.pt"
    weights.write_bytes(weights.read_bytes()[: weights.stat().st_size // 2])  # as a kill mid-write would
    torn = run / "checkpoints" / "0000009999"  # a newer one whose state.json was never written
    shutil.copytree(older, torn)
    (torn / "state.json").unlink()
    res = CliRunner().invoke(app, ["run", "--resume", str(run), "--timesteps", "1024", "--no-progress"])
    assert res.exit_code == 0, res.output
    assert f"skipped damaged checkpoint {torn}: no state.json" in res.output
    assert f"skipped damaged checkpoint {newest}: weights.pt is damaged" in res.output
    res = CliRunner().invoke(app, ["repair", str(run)])
    assert res.exit_code == 0 and "valid" in res.output, res.output

    # `fastrl eval` of the run, stopped by SIGTERM once it is well into its episodes: a plain stop, nothing written
    imports = import_cpu_seconds()  # a SIGTERM before the handlers are set kills at the default: wait past them
    proc = start(["eval", str(run), "--episodes", "200", "-o", str(run / "again.json")], run, quiet=False)
    wait_until(lambda: cpu_seconds(proc.pid) > imports + 3.0, proc)
    proc.terminate()
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "Traceback" not in err, err
    *notes, stopped, again = err.splitlines()  # first a note per damaged checkpoint, as every command reading a run
    assert [stopped, again] == [
        "SIGTERM: evaluation stopped; nothing was written",
        f"evaluate again with: fastrl eval {run}",
    ]
    torn_note = f"note: {torn}: no state.json (it was being written when the run stopped); resume continues from"
    assert notes == [f"{torn_note} {latest_checkpoint(run)}"]
    assert not (run / "again.json").exists()


def import_cpu_seconds() -> float:
    """CPU seconds a fresh process spends importing what `fastrl eval` imports before it sets its stop handlers."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    code = "import fastrl.cli, fastrl.cli.training, fastrl.runner, fastrl.runner.runs.saved, torch"
    subprocess.run([sys.executable, "-c", code], check=True, env={**os.environ, "CI": "1", "MUJOCO_GL": "egl"})
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def cpu_seconds(pid: int) -> float:
    """CPU time a process has used so far (user + system), from /proc."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def test_atomic_writes_leave_the_old_file_when_writing_fails(tmp_path):
    path = write_json(tmp_path / "meta.json", {"status": "training"})

    def half_then_fail(f):
        f.write(b'{"status": "do')
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(path, half_then_fail)
    assert json.loads(path.read_text()) == {"status": "training"}
    assert [p.name for p in tmp_path.iterdir()] == ["meta.json"]

    def no_space(f):
        raise OSError(28, "No space left on device")

    with pytest.raises(DiskFull, match=r"writing .*meta\.json needs"):
        atomic_write(path, no_space, needed=10)
    assert json.loads(path.read_text()) == {"status": "training"}


@pytest.fixture
def small_disk(tmp_path):
    """A 64 MB tmpfs mounted for the test (skipped where mounting is not permitted)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    res = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64m", "tmpfs", str(disk)], capture_output=True, text=True)
    if res.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({res.stderr.strip() or 'mount failed'}): needs root")
    yield disk
    subprocess.run(["umount", "-l", str(disk)], capture_output=True)


def fill(disk: Path, leave: int) -> Path:
    """Fill the file system up to `leave` free bytes with one file; return it."""
    filler = disk / "filler"
    with open(filler, "wb") as f:
        block = b"\0" * (1 << 20)
        while (free := shutil.disk_usage(disk).free) > leave:
            try:
                f.write(block[: max(1, min(len(block), free - leave))])
                f.flush()
            except OSError:
                break
    return filler


def to_bytes(size: str) -> float:
    """'1.5 MB' or '300 kB' as bytes."""
    number, unit = size.split()
    return float(number) * {"kB": 1e3, "MB": 1e6}[unit]


def stopped_for_space(proc: subprocess.Popen, run: Path) -> str:
    """Wait for the stop on a full disk and check its message: plain sentences, no traceback or Rerun log line."""
    try:
        _, err = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)  # faulthandler prints where every thread is
        stacks = proc.communicate()[1].split("Extension modules:")[0]  # the threads, not the module list after them
        pytest.fail(f"no stop within 120 s on a full disk: {stacks[-6000:]}")
    assert proc.returncode == 1, err
    lines = err.strip().splitlines()
    assert "Traceback" not in err and "ERROR" not in err and "re_" not in err, err
    assert lines[0].startswith(f"stopped: the disk holding {run} is full (") and "free at least" in lines[0], err
    assert lines[-1] == f"resume with: fastrl run --resume {run}"
    return err


def test_a_full_disk_stops_in_a_sentence_and_the_run_resumes_once_space_is_freed(small_disk):
    """Nearly full (less than the reserve left): a clean stop with a whole recording; then full to the last byte."""
    runs = small_disk / "runs"
    proc = start(["run", SPEC, "--timesteps", "100000", "--runs", str(runs), *sets()], small_disk.parent)
    run = reach("training", runs, proc)
    filler = fill(small_disk, 500_000)
    err = stopped_for_space(proc, run)
    assert "is valid up to its last complete chunk" in err
    verify(run / "recording.rrd")
    assert status(run) == "stopped: disk full"

    filler.unlink()
    reached = checkpoint_timesteps(run)
    proc = start(["run", "--resume", str(run), "--timesteps", "100000"], small_disk.parent)
    wait_until(lambda: newer_checkpoint(run, reached), proc)
    filler = fill(small_disk, 0)
    err = stopped_for_space(proc, run)
    free, needed = re.search(r"\(([\d.]+ [kM]B) free\).*free at least ([\d.]+ [kM]B)", err).groups()
    assert to_bytes(free) < to_bytes(
        needed
    )  # what was free then (a checkpoint rotation may free a little after the fill)
    assert "is valid up to its last complete chunk" in err or f"(or: fastrl repair {run}) rewrites it" in err

    filler.unlink()
    resume(run)
    verify(*(run / f"recording{part}.rrd" for part in ("", ".part1", ".part2")))


def test_a_stop_during_a_deferred_block_is_raised_when_the_block_is_done():
    before = signal.getsignal(signal.SIGINT)  # Python's handler, or SIG_IGN in a suite started in the background
    done = []
    with pytest.raises(KeyboardInterrupt):
        with stop_on_sigterm():
            with deferred():  # as a periodic checkpoint is written
                signal.raise_signal(signal.SIGINT)
                time.sleep(0.01)  # a Python handler would have raised here
                done.append("the block went on")
            done.append("not reached")
    assert done == ["the block went on"]
    assert signal.getsignal(signal.SIGINT) is before  # the handlers of before are back
