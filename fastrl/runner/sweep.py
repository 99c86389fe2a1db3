"""A grid sweep on Ray Tune: every trial an ordinary run in its own directory under the sweep folder."""

from __future__ import annotations

import io
import itertools
import json
import os
import shutil
import socket
import time
from datetime import UTC, datetime
from pathlib import Path

import yaml
from rich.console import Console

from ..model.compiler import compile_task
from ..spec import SpecError, SpecIssue, load_spec
from .rundir import latest_checkpoint
from .runfiles import RunFileError, read_eval, read_meta

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


def run_trial(config: dict) -> None:
    """Ray Tune trainable: one ordinary run into its directory (resumed from a checkpoint, skipped if finished)."""
    import ray
    import torch
    from ray import tune

    from .run import resume_run, start_run

    cpus = int(config["cpus"])
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(cpus)
    torch.set_num_threads(cpus)
    trial, run = config["trial"], Path(config["sweep"]) / config["trial"]["name"]
    with (Path(config["sweep"]) / "attempts.log").open("a") as log:
        log.write(f"{trial['name']} {datetime.now(UTC).isoformat(timespec='seconds')}\n")
    node = ray.get_runtime_context().get_node_id()
    t0 = time.perf_counter()
    if not is_finished(run):
        quiet = Console(file=io.StringIO())
        if latest_checkpoint(run) is not None:
            resume_run(run, quiet, progress=False)
        else:
            if run.is_dir():  # a failed or interrupted attempt that left no checkpoint
                shutil.rmtree(run)
            overrides = [*trial_overrides(trial), f"train.workers={cpus}"]  # no env processes beyond its CPUs
            start_run(Path(config["sweep"]) / "spec.yaml", overrides, console=quiet, progress=False, into=run)
        info = {"trial": trial, "node_id": node, "host": socket.gethostname(), "pid": os.getpid()}
        info |= {"wall_s": time.perf_counter() - t0, "torch_threads": torch.get_num_threads()}
        (run / "trial.json").write_text(json.dumps(info, indent=2))
    agent = read_eval(run)["agent"]
    tune.report(
        {
            "success": agent["success_rate"],
            "subtasks": agent["subtasks_completed"],
            "return": agent["return_mean"],
            "node_id": json.loads((run / "trial.json").read_text())["node_id"],
        }
    )


def _ray_init(address: str | None, cpus: int) -> bool:
    """Join the cluster at `address` (or RAY_ADDRESS), else start a local Ray; no dashboard, no usage reporting.

    Returns whether this call connected (and so should disconnect)."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    os.environ.setdefault("RAY_AIR_NEW_OUTPUT", "0")  # the classic reporter: silent at verbose=0
    address = address or os.environ.get("RAY_ADDRESS") or None
    if not address:  # a local Ray talks over loopback only (else Ray picks the machine's network address)
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
    try:
        import ray
    except ImportError:
        raise SweepError("fastrl sweep needs Ray Tune: pip install 'fastrl[sweep]'") from None
    if ray.is_initialized():
        return False
    if address:
        ray.init(address=address, log_to_driver=False, logging_level="WARNING")
    else:
        ray.init(
            num_cpus=max(os.cpu_count() or 1, cpus),
            include_dashboard=False,
            log_to_driver=False,
            logging_level="WARNING",
        )
    return True


def _tune_callback():
    """A Tune callback printing one line per finished, retried or failed trial (picklable: plain print)."""
    from ray import tune

    class Lines(tune.Callback):
        def on_trial_complete(self, iteration, trials, trial, **info):
            r = trial.last_result
            print(
                f"done   {trial.config['trial']['name']}  success {r.get('success', float('nan')):.0%}  "
                f"subtasks {r.get('subtasks', float('nan')):.0%}  node {str(r.get('node_id', '?'))[:8]}",
                flush=True,
            )

        def on_trial_recover(self, iteration, trials, trial, **info):
            print(f"failed {trial.config['trial']['name']}: retrying once", flush=True)

        def on_trial_error(self, iteration, trials, trial, **info):
            print(f"failed {trial.config['trial']['name']} (after its retry)", flush=True)

    return Lines()


def run_sweep(sweep: Path, address: str | None = None, console: Console | None = None) -> list[dict]:
    """Run every unfinished trial of a sweep folder on Ray Tune (one retry each); return the failed trials."""
    sweep = Path(sweep).resolve()
    manifest = read_manifest(sweep)
    console = console or Console()
    cpus = int(manifest["cpus_per_trial"])
    todo = [t for t in manifest["trials"] if not is_finished(sweep / t["name"])]
    done = len(manifest["trials"]) - len(todo)
    console.print(f"{len(manifest['trials'])} trials, {done} already finished, {len(todo)} to run", markup=False)
    if not todo:
        return []
    connected = _ray_init(address, cpus)
    try:
        return _fit(sweep, todo, cpus)
    finally:
        if connected:
            import ray

            ray.shutdown()


def _fit(sweep: Path, todo: list[dict], cpus: int) -> list[dict]:
    """One Tune experiment over the given trials, each retried once; the failed ones with their last error line."""
    from ray import tune

    k = 1 + len(list(sweep.glob("tune-*")))
    tuner = tune.Tuner(
        tune.with_resources(run_trial, {"cpu": cpus}),
        param_space={"trial": tune.grid_search(todo), "sweep": str(sweep), "cpus": cpus},
        # reuse_actors: a worker keeps its imports (torch, SB3, MuJoCo) from one trial to the next
        tune_config=tune.TuneConfig(trial_dirname_creator=lambda t: t.config["trial"]["name"], reuse_actors=True),
        run_config=tune.RunConfig(
            name=f"tune-{k}",
            storage_path=str(sweep),
            failure_config=tune.FailureConfig(max_failures=1),
            verbose=0,
            callbacks=[_tune_callback()],
        ),
    )
    results = tuner.fit()
    failed = []
    for r in results:
        if r.error is not None:
            last = (str(r.error).strip().splitlines() or ["?"])[-1]
            failed.append({"trial": r.config["trial"]["name"], "error": last})
    return failed
