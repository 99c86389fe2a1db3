"""The run directory: naming, resolved spec, compiled MJCF, metadata, checkpoints, listing."""

from __future__ import annotations

import platform
import shutil
import subprocess
import sys
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path

import yaml

from ...about import DISTRIBUTION
from ...agents.sb3 import checkpoint_problem
from ...atomic import write_json, write_text
from ...spec import spec_hash
from ...spec.models import TaskSpec
from .runfiles import read_eval, read_meta, read_run_spec, read_state, run_problems

PACKAGES = (DISTRIBUTION, "mujoco", "gymnasium", "stable-baselines3", "torch", "numpy", "pydantic", "rerun-sdk")


def new_run_dir(root: Path, spec: TaskSpec, label: str | None = None) -> Path:
    """runs/<spec name>/<UTC timestamp>-<algo>-s<seed>/ (algo e.g. ppo, airl-ppo, bc) or <timestamp>-<label>/,
    made unique if it exists."""
    stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
    algo = (
        spec.train.algo.lower()
        if not spec.irl.enabled
        else ("bc" if spec.irl.algorithm == "bc" else f"{spec.irl.algorithm}-{spec.train.algo.lower()}")
    )
    base = Path(root) / spec.name / (f"{stamp}-{label}" if label else f"{stamp}-{algo}-s{spec.train.seed}")
    path, k = base, 1
    while path.exists():
        k += 1
        path = base.with_name(f"{base.name}-{k}")
    path.mkdir(parents=True)
    return path


def write_spec(run: Path, spec: TaskSpec, xml: str) -> None:
    """Write the resolved spec (YAML) and the compiled MJCF."""
    text = yaml.safe_dump(spec.model_dump(mode="json"), sort_keys=False, default_flow_style=None, width=100)
    write_text(run / "spec.yaml", f"# resolved spec of this run (hash {spec_hash(spec)})\n{text}")
    write_text(run / "model.xml", xml)


def git_commit() -> str | None:
    """The source tree's git commit, with '-dirty' if it has uncommitted changes, or None (installed from a wheel)."""
    root = Path(__file__).resolve().parents[3]
    if not (root / "pyproject.toml").is_file():  # site-packages, maybe inside some other project's repository
        return None
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, timeout=5)
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=root,
            capture_output=True,
            text=True,
            timeout=5,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    if head.returncode != 0:
        return None
    return head.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")


def write_meta(run: Path, spec: TaskSpec, source: str, extra: dict | None = None) -> dict:
    """meta.json: versions, git commit, command line, spec hash and source, machine."""
    versions = {}
    for pkg in PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = None
    meta = {
        "spec_name": spec.name,
        "spec_hash": spec_hash(spec),
        "spec_source": source,
        "algo": spec.train.algo,
        "seed": spec.train.seed,
        "timesteps": spec.train.timesteps,
        "command": sys.argv,
        "git_commit": git_commit(),
        "python": sys.version.split()[0],
        "versions": versions,
        "machine": {"platform": platform.platform(), "processor": platform.processor(), "cpus": _cpu_count()},
        "started_utc": datetime.now(UTC).isoformat(timespec="seconds"),
        **(extra or {}),
    }
    write_json(run / "meta.json", meta)
    return meta


def update_meta(run: Path, **fields) -> None:
    """Merge fields into meta.json."""
    path = run / "meta.json"
    meta = read_meta(run) if path.exists() else {}
    meta.update(fields)
    write_json(path, meta)


def rebuild_meta(run: Path) -> Path:
    """Replace a damaged meta.json (kept beside it, renamed) by one rebuilt from spec.yaml and the newest checkpoint;
    return where the damaged one went."""
    spec = read_run_spec(run)
    kept, k = run / "meta.json.damaged", 1
    while kept.exists():
        k += 1
        kept = run / f"meta.json.damaged-{k}"
    (run / "meta.json").rename(kept)
    ckpt = latest_checkpoint(run)
    state = read_state(ckpt) if ckpt else {"timesteps": 0}
    started = datetime.fromtimestamp((run / "spec.yaml").stat().st_mtime, UTC).isoformat(timespec="seconds")
    finished = (run / "eval.json").exists() and checkpoint_problem(run / "final") is None
    extra = {
        "status": "done" if finished else "interrupted",
        "trained_timesteps": state["timesteps"],
        "train_seconds": state.get("train_seconds"),
    }
    write_meta(run, spec, "unknown (meta.json rebuilt by fastrl repair)", {**extra, "started_utc": started})
    return kept


def latest_checkpoint(run: Path, skipped: list[str] | None = None) -> Path | None:
    """The whole checkpoint with the most timesteps, or None; damaged ones are named in `skipped` and passed over."""
    found = sorted((run / "checkpoints").glob("[0-9]*"), key=lambda p: p.name, reverse=True)
    for path in found:
        problem = checkpoint_problem(path)
        if problem is None:
            return path
        if skipped is not None:
            skipped.append(f"{path}: {problem}")
    return None


def clean_leftovers(run: Path) -> list[Path]:
    """Remove the hidden temporary files and directories a kill left mid-write (they are never read); return them."""
    found = [
        p
        for folder in (run, run / "checkpoints", run / "networks")
        for p in folder.glob(".*")
        if any(tag in p.name for tag in (".tmp-", ".old-", ".repair-"))
    ]
    for p in found:
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
    return found


def list_runs(root: Path) -> list[dict]:
    """Every run under root with its headline figures, newest first; damaged files are named in `problems`."""
    rows = []
    found = {p.parent for name in ("meta.json", "spec.yaml") for p in Path(root).glob(f"*/*/{name}")}
    for run in found:
        problems = run_problems(run)
        damaged = {p.path.name for p in problems}
        meta = read_meta(run) if "meta.json" not in damaged and (run / "meta.json").exists() else {}
        ev = read_eval(run)["agent"] if "eval.json" not in damaged and (run / "eval.json").exists() else {}
        rows.append(
            {
                "run": str(run),
                "spec": meta.get("spec_name"),
                "algo": meta.get("algo"),
                "seed": meta.get("seed"),
                "status": "damaged" if problems else str(meta.get("status", "?")),
                "timesteps": meta.get("trained_timesteps"),
                "wall_s": meta.get("train_seconds"),
                "success": ev.get("success_rate"),
                "subtasks": ev.get("subtasks_completed"),
                "started": str(meta.get("started_utc", "")),
                "problems": [str(p) for p in problems],
            }
        )
    return sorted(rows, key=lambda r: r["started"], reverse=True)


def _cpu_count() -> int:
    """Number of CPUs."""
    import os

    return os.cpu_count() or 1
