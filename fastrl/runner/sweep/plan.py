"""A sweep's plan and folder: configurations x seeds, each trial an ordinary run in its own directory under it."""

from __future__ import annotations

import itertools
import json
from datetime import UTC, datetime
from pathlib import Path

import yaml

from ...model.compiler import compile_task
from ...spec import SpecError, SpecIssue, load_spec
from ..runs.runfiles import RunFileError, read_eval, read_meta

MANIFEST = "sweep.json"


class SweepError(Exception):
    """A sweep cannot start or resume (bad grid, no manifest); the message is one line for the user."""


def parse_grid(items: list[str]) -> dict[str, list[str]]:
    """`KEY=V1,V2` strings as {key: [values]} in the order given."""
    grid: dict[str, list[str]] = {}
    for item in items:
        key, sep, values = item.partition("=")
        key = key.strip()
        vals = [v.strip() for v in values.split(",") if v.strip()]
        if not sep or not key or not vals:
            raise SweepError(f"--grid {item!r}: expected KEY=V1,V2,...")
        if key in grid:
            raise SweepError(f"--grid {key} is given twice")
        grid[key] = vals
    return grid


def parse_seeds(text: str) -> list[int]:
    """`0,1,2` as [0, 1, 2]."""
    try:
        seeds = [int(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise SweepError(f"--seeds {text!r}: expected integers like 0,1,2") from None
    if not seeds or len(set(seeds)) != len(seeds):
        raise SweepError(f"--seeds {text!r}: expected distinct integers like 0,1,2")
    return seeds


def _label(key: str, value: str) -> str:
    """A file-name-safe `leaf=value` for a trial directory."""
    safe = "".join(c if c.isalnum() or c in ".-+" else "-" for c in value)
    return f"{key.split('.')[-1]}={safe}"


def settings_of(grid: dict[str, list[str]]) -> list[dict[str, str]]:
    """Every configuration of a grid (its product), as {key: value}."""
    return [dict(zip(grid, values)) for values in (itertools.product(*grid.values()) if grid else [()])]


def grid_of(settings: list[dict[str, str]]) -> dict[str, list[str]]:
    """The keys that configurations listed one by one set, and their values in order of appearance; a SweepError
    unless every configuration sets the same keys (the results table has a column per key)."""
    keys = list(settings[0]) if settings else []
    grid: dict[str, list[str]] = {k: [] for k in keys}
    for setting in settings:
        if set(setting) != set(keys):
            raise SweepError(f"configuration {setting} sets other keys than {keys}: every one must set the same keys")
        for k in keys:
            grid[k] += [] if str(setting[k]) in grid[k] else [str(setting[k])]
    return grid


def plan(
    grid: dict[str, list[str]], seeds: list[int], settings: list[dict[str, str]] | None = None
) -> tuple[list[dict], list[dict]]:
    """The configurations (the grid's product, or `settings` one by one) and the trials (configuration x seed),
    each with its directory name."""
    configs = []
    for i, setting in enumerate(settings_of(grid) if settings is None else settings):
        setting = {k: str(v) for k, v in setting.items()}
        label = "_".join(_label(k, v) for k, v in setting.items()) or "base"
        configs.append({"index": i, "name": f"c{i}_{label}", "setting": setting})
    trials = [
        {"name": f"{c['name']}_s{seed}", "config": c["index"], "seed": seed, "setting": c["setting"]}
        for c in configs
        for seed in seeds
    ]
    return configs, trials


def trial_overrides(trial: dict) -> list[str]:
    """The --set overrides of one trial: its configuration's values and its seed."""
    return [f"{k}={v}" for k, v in trial["setting"].items()] + [f"train.seed={trial['seed']}"]


def is_finished(run: Path) -> bool:
    """Whether a trial's run directory holds a finished run (status done, eval.json written)."""
    if not ((run / "meta.json").exists() and (run / "eval.json").exists()):
        return False
    try:  # a damaged meta.json or eval.json: not finished, so --resume resumes the trial and rewrites them
        return read_meta(run).get("status") == "done" and bool(read_eval(run))
    except RunFileError:
        return False


def create_sweep(
    spec_path: Path,
    overrides: list[str],
    grid: dict[str, list[str]],
    seeds: list[int],
    cpus: int,
    out: Path,
    settings: list[dict[str, str]] | None = None,
) -> Path:
    """Validate every configuration, write the sweep folder's resolved base spec and manifest; return the folder.

    `settings`: the configurations one by one ({key: value} each, all setting the same keys) instead of the
    product of `grid` (then left empty), for combinations a product cannot give (Fig. 5's ablations)."""
    if cpus < 1:
        raise SweepError(f"--cpus-per-trial {cpus}: must be at least 1")
    if settings is not None:
        if grid:
            raise SweepError("give a grid or configurations one by one, not both")
        if not settings:
            raise SweepError("no configuration given")
        grid = grid_of(settings)
    base = load_spec(spec_path, overrides)
    if any(k == "train.seed" for k in grid):
        raise SweepError("--grid train.seed: give seeds with --seeds instead")
    configs, trials = plan(grid, seeds, settings)
    for c in configs:
        try:
            compile_task(load_spec(spec_path, [*overrides, *trial_overrides({**c, "seed": seeds[0]})]))
        except ValueError as e:  # MuJoCo compile errors
            detail = " ".join(str(e).split())
            raise SpecError(
                [SpecIssue(str(spec_path), None, "", f"MuJoCo cannot compile {c['name']}: {detail}")]
            ) from None
    out = Path(out)
    if out.exists() and any(out.iterdir()):
        raise SweepError(f"{out} exists and is not empty: give another -o, or --resume {out}")
    out.mkdir(parents=True, exist_ok=True)
    text = yaml.safe_dump(base.model_dump(mode="json"), sort_keys=False, default_flow_style=None, width=100)
    (out / "spec.yaml").write_text(f"# resolved base spec of this sweep (from {spec_path})\n{text}")
    manifest = {
        "spec_source": str(spec_path),
        "spec_name": base.name,
        "overrides": list(overrides),
        "grid": grid,
        "seeds": seeds,
        "cpus_per_trial": cpus,
        "configs": configs,
        "trials": trials,
        "created_utc": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    (out / MANIFEST).write_text(json.dumps(manifest, indent=2))
    return out


def read_manifest(sweep: Path) -> dict:
    """The sweep folder's manifest, or a SweepError naming what is missing."""
    path = Path(sweep) / MANIFEST
    if not path.exists():
        raise SweepError(f"{sweep} is not a sweep folder (no {MANIFEST})")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as e:
        raise SweepError(f"{path}:{e.lineno}: not valid JSON ({e.msg})") from None
