"""The paper's laparoscopic study (Table 3): a graded cohort, inverse RL on its best, learned scores against economy and
safety."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import numpy as np
from rich.console import Console
from scipy.stats import spearmanr

from ..assess.scoring import Scorer, TrajectoryScores
from ..atomic import write_json
from ..data.cohort import make_cohort
from ..data.trajectory import Trajectory, load_files
from ..irl.networks import has_networks, load_networks
from ..log.study import log_study, plot_correlations
from ..model.compiler import CompiledTask, compile_task
from ..model.scope import joint_ranges
from ..spec import load_spec
from ..spec.models import TaskSpec
from .bars import counting_bar
from .runs.rundir import latest_checkpoint, new_run_dir, update_meta, write_meta, write_spec
from .runs.runfiles import STUDY_KIND, STUDY_RESULT
from .runs.stops import stop_on_sigterm

METRICS = ("economy", "safety")
LEARNED = ("reward", "value")


def start_study(
    spec_path,
    overrides=(),
    root="runs",
    console: Console | None = None,
    progress: bool = True,
    task: CompiledTask | None = None,
) -> Path:
    """Run the spec's study in a new run directory; return it (`task`: the spec compiled already)."""
    if task is None:
        task = compile_task(load_spec(spec_path, overrides))
    spec = task.spec
    run = new_run_dir(Path(root), spec, label=f"study-s{spec.study.seed}")
    write_spec(run, spec, task.xml)
    write_meta(run, spec, str(spec_path), {"status": "cohort", "overrides": list(overrides), "kind": STUDY_KIND})
    return run_study(run, console or Console(), progress)


@stop_on_sigterm()
def run_study(run: Path, console: Console, progress: bool) -> Path:
    """Run (or continue, stage by stage) the study of a run directory: what is done is not redone."""
    spec = load_spec(run / "spec.yaml")
    timings = {}
    t0 = time.perf_counter()
    cohort = write_cohort(spec, run / "cohort", console, progress)
    timings["cohort"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    heuristic = Scorer(spec)
    scored = _score_all(heuristic, cohort, "heuristic scores", console, progress)
    best = pick_best(scored, spec.study.best)
    _copy_best(cohort, best, run / "best")
    timings["heuristic"] = time.perf_counter() - t0
    learned = {}
    for algo in spec.study.algorithms:
        update_meta(run, status=f"inverse RL: {algo}")
        t0 = time.perf_counter()
        sub = train_irl(run, algo, console, progress)
        timings[f"irl_{algo}"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        scorer = Scorer(spec, load_networks(sub / "networks"))
        learned[algo] = _score_all(scorer, cohort, f"{algo} scores", console, progress)
        timings[f"score_{algo}"] = time.perf_counter() - t0
    result = study_result(spec, scored, learned, best, timings)
    write_json(run / STUDY_RESULT, result)
    plot_correlations(result, run / "table3.png")
    log_study(run / "recording.rrd", run.name, compile_task(spec), scored, learned, result, figure=run / "table3.png")
    update_meta(run, status="done", seconds=timings)
    return run


def write_cohort(spec: TaskSpec, folder: Path, console: Console, progress: bool) -> list[tuple[str, Trajectory]]:
    """The cohort's trajectories, generated into `folder` unless already there; (name, trajectory) in order."""
    cfg = spec.study
    n = cfg.levels * cfg.per_level
    paths = sorted(folder.glob("*.npz"))
    if len(paths) < n:
        folder.mkdir(parents=True, exist_ok=True)
        with counting_bar(console, progress) as bar:
            task = bar.add_task("synthetic cohort", total=n)
            for traj in make_cohort(spec, cfg.levels, cfg.per_level, cfg.seed):
                traj.save(folder / f"{traj.meta['subject']}.npz")
                bar.advance(task)
        paths = sorted(folder.glob("*.npz"))
    loaded, errors = load_files(paths, joint_ranges(spec.scope))
    for message in errors:  # a damaged file is named and left out; the rest of the cohort goes on
        console.print(f"skipped {message}", markup=False, highlight=False, style="yellow")
    return [(p.stem, traj) for p, traj in loaded]


def pick_best(scored: list[TrajectoryScores], k: int) -> list[str]:
    """Names of the k trajectories with the highest heuristic return (ties: the earlier name)."""
    order = sorted(scored, key=lambda s: (-s.scores["heuristic"], s.name))
    return [s.name for s in order[:k]]


def _copy_best(cohort, best: list[str], folder: Path) -> None:
    """Copy the chosen trajectories into `folder` (the demonstrations of inverse RL)."""
    folder.mkdir(exist_ok=True)
    for name, traj in cohort:
        if name in best and not (folder / f"{name}.npz").exists():
            traj.save(folder / f"{name}.npz")


def train_irl(run: Path, algo: str, console: Console, progress: bool) -> Path:
    """Train (or resume, or reuse) inverse RL on the best procedures; return its run directory."""
    from .train.run import resume_run, start_run

    sub = run / algo
    if has_networks(sub / "networks") and (sub / "eval.json").exists():
        return sub
    if sub.exists() and latest_checkpoint(sub) is not None:
        return resume_run(sub, console, progress)
    if sub.exists():
        shutil.rmtree(sub)  # started but not one checkpoint written: start again
    spec = load_spec(run / "spec.yaml")
    console.print(
        f"[bold]{algo.upper()}[/bold] on the {spec.study.best} best procedures, "
        f"{spec.study.timesteps:,} generator steps"
    )
    overrides = [
        f"irl.algorithm={algo}",
        f"irl.demonstrations.path={run / 'best'}",
        f"train.timesteps={spec.study.timesteps}",
        "study.enabled=false",
    ]
    generator = spec.irl.generator
    if generator is not None and generator.recorded_starts:  # the whole cohort's states as training starts
        overrides.append(f"irl.demonstrations.others={run / 'cohort'}")
    return start_run(run / "spec.yaml", overrides, console=console, progress=progress, into=sub)


def _score_all(scorer: Scorer, cohort, label: str, console: Console, progress: bool) -> list[TrajectoryScores]:
    """Replay and score every trajectory of the cohort."""
    out = []
    with counting_bar(console, progress) as bar:
        task = bar.add_task(label, total=len(cohort))
        for name, traj in cohort:
            out.append(scorer.score(traj, name))
            bar.advance(task)
    return out


def correlation(x, y) -> dict:
    """Spearman's rho and its two-sided p-value (None if either side is constant)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if np.ptp(x) == 0 or np.ptp(y) == 0:
        return {"rho": None, "p": None}
    r = spearmanr(x, y)
    return {"rho": float(r.statistic), "p": float(r.pvalue)}


def study_result(
    spec: TaskSpec, heuristic: list[TrajectoryScores], learned: dict, best: list[str], timings: dict
) -> dict:
    """Table 3 (learned reward and value against economy and safety) and the per-procedure figures."""
    rows = [
        {
            "name": s.name,
            "skill": s.skill,
            "heuristic": s.scores["heuristic"],
            "subtasks": s.scores["subtasks"],
            "time": s.scores["time"],
            **{k: s.scores[k] for k in (*METRICS, "contacts")},
            "best": s.name in best,
        }
        for s in heuristic
    ]
    for algo, scored in learned.items():
        for row, s in zip(rows, scored):
            row.update({f"{algo}_{k}": s.scores[k] for k in LEARNED})
    table = {
        algo: {
            f"{k}-{m}": correlation([r[f"{algo}_{k}"] for r in rows], [r[m] for r in rows])
            for k in LEARNED
            for m in METRICS
        }
        for algo in learned
    }
    table["heuristic"] = {
        f"heuristic-{m}": correlation([r["heuristic"] for r in rows], [r[m] for r in rows]) for m in METRICS
    }
    skill = {
        algo: {k: correlation([r[f"{algo}_{k}"] for r in rows], [r["skill"] for r in rows]) for k in LEARNED}
        for algo in learned
    }
    return {
        "spec": spec.name,
        "n": len(rows),
        "best": best,
        "table3": table,
        "against_skill": skill,
        "metrics": {
            "economy": "total camera distance inside the cavity (m)",
            "safety": "sum over samples of the camera's distance to the closest anatomy vertex (m)",
            "contacts": "samples with the scope touching anatomy or walls",
            "reward": "sum of the learned reward r_psi over the procedure",
            "value": "mean learned value V over the procedure",
        },
        "seconds": timings,
        "procedures": rows,
    }
