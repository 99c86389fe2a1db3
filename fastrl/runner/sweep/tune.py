"""A sweep folder's unfinished trials run on Ray Tune, a local Ray or a cluster, each retried once."""

from __future__ import annotations

import os
from pathlib import Path

from rich.console import Console

from .plan import SweepError, is_finished, read_manifest
from .trial import run_trial


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
    """One Tune run over the given trials, each retried once; the failed ones with their last error line."""
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
