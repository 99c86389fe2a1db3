"""The one reader of a run directory's files: each fault named in one line with what to do; nothing is written."""

from __future__ import annotations

import json
import os
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...agents.checkpoint_files import checkpoint_problem
from ...spec import SpecError, load_spec
from ...spec.models import TaskSpec

MAX_JSON_BYTES = 64 * 1024 * 1024  # meta.json, eval.json, state.json are kilobytes
RRD_TRAILER = struct.Struct("<QQI8sI")  # rerun 0.41: footer offset, footer length, checksum, b"RRF2FOOT", version
RRD_MAGIC = b"RRF2FOOT"
# A study's Table 3 and its meta.json kind keep the names of runs written when a study was called an experiment.
STUDY_RESULT = "experiment.json"
STUDY_KIND = "experiment"


@dataclass(frozen=True)
class RunProblem:
    """A damaged or missing file of a run: which, what is wrong, what to do."""

    path: Path
    fault: str
    advice: str

    def __str__(self) -> str:
        return f"{self.path}: {self.fault}; {self.advice}"


class RunFileError(ValueError):
    """A file a command needs is damaged; str() is one line naming it, the fault and what to do."""

    def __init__(self, problem: RunProblem):
        super().__init__(str(problem))
        self.problem = problem


def _repair(run: Path) -> str:
    return f"mend it with: fastrl repair {run}"


def read_json(path: Path, advice: str) -> dict:
    """A JSON object file; RunFileError if it is missing, unreadable, torn or not an object."""
    try:
        if path.stat().st_size > MAX_JSON_BYTES:
            raise RunFileError(RunProblem(path, f"larger than {MAX_JSON_BYTES:,} bytes", advice))
        data = json.loads(path.read_bytes().decode("utf-8"))
    except FileNotFoundError:
        raise RunFileError(RunProblem(path, "missing", advice)) from None
    except OSError as e:
        raise RunFileError(RunProblem(path, f"cannot be read ({e.strerror or e})", advice)) from None
    except UnicodeDecodeError as e:
        raise RunFileError(RunProblem(path, f"not text (bad byte at offset {e.start})", advice)) from None
    except ValueError as e:  # json.JSONDecodeError: half written by a disk or copy fault
        raise RunFileError(RunProblem(path, f"damaged: not valid JSON ({e})", advice)) from None
    if not isinstance(data, dict):
        raise RunFileError(RunProblem(path, f"damaged: a JSON {type(data).__name__}, not an object", advice))
    return data


def read_meta(run: Path) -> dict:
    """meta.json of a run."""
    return read_json(Path(run) / "meta.json", _repair(run))


def read_eval(run: Path) -> dict:
    """eval.json of a run, with the agent's figures."""
    path = Path(run) / "eval.json"
    advice = f"evaluate again with: fastrl eval {run} -o {path}"
    data = read_json(path, advice)
    if not isinstance(data.get("agent"), dict):
        raise RunFileError(RunProblem(path, "damaged: no 'agent' figures", advice))
    return data


def read_state(checkpoint: Path) -> dict:
    """state.json of a checkpoint, with its timesteps."""
    path = Path(checkpoint) / "state.json"
    advice = f"resume passes over this checkpoint (see: fastrl repair {Path(checkpoint).parent.parent})"
    data = read_json(path, advice)
    if not isinstance(data.get("timesteps"), int):
        raise RunFileError(RunProblem(path, "damaged: no whole number of timesteps", advice))
    return data


def read_run_spec(run: Path, overrides=()) -> TaskSpec:
    """The run's resolved spec.yaml (FileNotFoundError: not a run directory; RunFileError: damaged)."""
    path = Path(run) / "spec.yaml"
    if not path.exists():
        raise FileNotFoundError(f"{run} is not a run directory (no spec.yaml)")
    try:
        return load_spec(path, overrides)
    except SpecError as e:
        first = e.errors[0]
        where = f"line {first.line}: " if first.line else ""
        fault = f"damaged: {where}{first.path + ': ' if first.path else ''}{' '.join(first.message.split())}"
        advice = "restore it from a copy, or start a new run from the spec named in meta.json (spec_source)"
        raise RunFileError(RunProblem(path, fault, advice)) from None


def read_metrics(run: Path) -> list[dict]:
    """metrics.jsonl's rows, each a mapping with whole-number timesteps; torn or foreign lines are left out."""
    path = Path(run) / "metrics.jsonl"
    try:
        text = path.read_bytes().decode("utf-8", "replace")
    except FileNotFoundError:
        return []
    except OSError as e:
        raise RunFileError(RunProblem(path, f"cannot be read ({e.strerror or e})", _repair(run))) from None
    rows = []
    for line in text.splitlines():
        try:
            row = json.loads(line)
        except ValueError:
            continue
        if isinstance(row, dict) and isinstance(row.get("timesteps"), int):
            rows.append(row)
    return rows


def recording_fault(path: Path) -> str | None:
    """Why an .rrd lacks its footer (cut short by a kill or a full disk), from its last bytes only; None if whole."""
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            if size < RRD_TRAILER.size:
                return "no RRD footer: the file is cut short"
            f.seek(size - RRD_TRAILER.size)
            offset, length, _, magic, _ = RRD_TRAILER.unpack(f.read(RRD_TRAILER.size))
    except OSError as e:
        return f"cannot be read ({e.strerror or e})"
    if magic != RRD_MAGIC or offset + length + RRD_TRAILER.size != size:
        return "no RRD footer: it was cut short by a kill or a full disk"
    return None


def recording_problem(run: Path) -> RunProblem | None:
    """The run's recording.rrd, if it exists and lacks its footer."""
    path = Path(run) / "recording.rrd"
    fault = recording_fault(path) if path.exists() else None
    return RunProblem(path, fault, _repair(run)) if fault else None


def checkpoint_problems(run: Path) -> list[RunProblem]:
    """final/ and every checkpoint that cannot be loaded (missing, torn, damaged files), with the one resume uses."""
    run = Path(run)
    found = sorted((run / "checkpoints").glob("[0-9]*"), key=lambda p: p.name, reverse=True)
    whole = next((p for p in found if checkpoint_problem(p) is None), None)
    going_on = f"resume continues from {whole}" if whole else "no whole checkpoint: resume starts from 0 timesteps"
    problems = [RunProblem(p, fault, going_on) for p in found if (fault := checkpoint_problem(p))]
    if (run / "final").exists() and (fault := checkpoint_problem(run / "final")):
        problems.append(RunProblem(run / "final", fault, f"`fastrl eval` uses the newest whole checkpoint; {going_on}"))
    return problems


def run_problems(run: Path, checkpoints: bool = True) -> list[RunProblem]:
    """Every damaged file of a run: spec.yaml, meta.json, eval.json, the recording, and (if asked) checkpoints."""
    run, problems = Path(run), []
    readers: list[tuple[str, Any]] = [("spec.yaml", read_run_spec), ("meta.json", read_meta), ("eval.json", read_eval)]
    for name, reader in readers:
        if (run / name).exists():
            try:
                reader(run)
            except RunFileError as e:
                problems.append(e.problem)
    rec = recording_problem(run)
    problems += [rec] if rec else []
    return problems + (checkpoint_problems(run) if checkpoints else [])


def require(run: Path, needed: set[str], checkpoints: bool = True) -> list[RunProblem]:
    """Raise RunFileError for the first damaged file among `needed` (names); return the others' problems."""
    problems = run_problems(run, checkpoints)
    for p in problems:
        if p.path.name in needed:
            raise RunFileError(p)
    return problems
