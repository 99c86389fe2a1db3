"""The assessment stage: score trajectories with a run's learned networks, write JSON, CSV, PNG and Rerun."""

from __future__ import annotations

import json
import time
from concurrent.futures import Future
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ..assess.figures import deviations, draw_path_figures, group_of, plot_distributions
from ..assess.references import expert_paths, references_for
from ..assess.report import build_report, csv_text, group_key, row, score_files, trajectory_files
from ..assess.scoring import Scorer, TrajectoryScores, normalise, with_learned
from ..irl.network_files import has_networks
from ..spec import load_spec
from .helper import Helper, score_shared


@dataclass
class Assessment:
    """What one `fastrl score` produced: the report and the files written."""

    report: dict
    files: dict[str, Path] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)


@dataclass
class Scored:
    """Every file scored (in file order), the problems, and what normalises the scores."""

    scored: list[TrajectoryScores]
    problems: list[str]
    references: dict
    recordings: list | None  # the recordings the run learned from (the upper reference), else None
    learned: bool


def load_scorer(run: Path | None, spec_path: Path | None, networks: bool = True) -> tuple[Scorer, str | None]:
    """A scorer for a run (its spec and, after inverse RL and if `networks`, its learned networks) or for a bare
    spec."""
    if run is not None:
        if not (run / "spec.yaml").exists():
            raise FileNotFoundError(f"{run} is not a run directory (no spec.yaml)")
        loaded = None
        if networks and has_networks(run / "networks"):
            from ..irl.networks import load_networks

            loaded = load_networks(run / "networks")
        return Scorer(load_spec(run / "spec.yaml"), loaded), run.name
    if spec_path is None:
        raise FileNotFoundError("give --run RUN_DIR (learned scores) or --spec SPEC (heuristic and kinematic only)")
    return Scorer(load_spec(spec_path)), None


def outputs_for(output: Path | None, run: Path | None) -> dict[str, Path]:
    """Where each product goes: next to `output` (a .json) or in RUN/assessment/ or ./assessment/."""
    if output is None:
        output = (run / "assessment" if run is not None else Path("assessment")) / "scores.json"
    stem, parent = output.stem, output.parent
    return {
        "json": output,
        "csv": parent / f"{stem}.csv",
        "paths": parent / f"{stem}_paths.png",
        "deviation": parent / f"{stem}_deviation.png",
        "distributions": parent / f"{stem}_distributions.png",
        "rrd": parent / f"{stem}.rrd",
    }


def score_here(scorer: Scorer, files: list[Path], episodes: int, cache: Path | None, on_file) -> Scored:
    """Score every file in this process."""
    references, recordings = references_for(scorer, episodes, cache)
    scored, problems = score_files(scorer, files, on_file=lambda _f: on_file())
    return Scored(scored, problems, references, recordings, scorer.learned)


def score_with_helper(
    helper: Helper,
    scorer: Scorer,
    files: list[Path],
    networks: Path | None,
    episodes: int,
    cache: Path | None,
    on_file,
    pictures: bool,
) -> Scored:
    """Score in two processes taking files from one counter. The worker loads the networks (so this process never
    imports torch) and the references first, then scores with them; this process replays meanwhile and has the
    worker evaluate its share's learned scores at the end, each trajectory on its own as in score_here.

    With `pictures`, each process first imports what it will draw with (matplotlib there, Rerun here): the counter
    shares out the files, so time spent importing now is made up by the other process scoring more."""
    prepared = helper.prepare(networks, episodes, cache, pictures)
    theirs = helper.score_share(files)
    if pictures:
        from ..log import assessment  # noqa: F401 (Rerun and the colour map)

    def after_file() -> bool:
        """Show progress; stop early if the worker could not load the networks."""
        on_file()
        return prepared.done() and prepared.exception() is not None

    mine = score_shared(files, helper.counter, scorer.replay_file, after_file)
    learned, references, recordings = prepared.result()  # the worker's error, if any, is raised here
    replayed = [r for _, r, _ in mine if r is not None]
    for (s, _), extra in zip(replayed, helper.learned([obs for _, obs in replayed]).result()):
        with_learned(s, extra)
    everything = sorted([(i, r and r[0], p) for i, r, p in mine] + theirs.result(), key=lambda e: e[0])
    scored = [s for _, s, _ in everything if s is not None]
    return Scored(scored, [p for _, _, p in everything if p is not None], references, recordings, learned)


def assess(
    inputs: list[Path],
    run: Path | None = None,
    spec_path: Path | None = None,
    output: Path | None = None,
    reference_episodes: int = 3,
    pictures: bool = True,
    console: Console | None = None,
    progress: bool = True,
    parallel: bool | None = None,
) -> Assessment:
    """Score every trajectory file under `inputs` and write the report and its pictures.

    `parallel`: score and draw in a second, forked process (None: when there are enough files and a second core)."""
    console = console or Console(stderr=True)
    files = trajectory_files(inputs)
    parallel = Helper.worth_it(len(files)) if parallel is None else parallel
    t0 = time.perf_counter()
    scorer, recording_id = load_scorer(run, spec_path, networks=not parallel)
    paths, seconds = outputs_for(output, run), {"load": time.perf_counter() - t0}
    networks = run / "networks" if run is not None and has_networks(run / "networks") else None
    cache = run / "assessment" / "references.json" if run is not None else None
    helper = Helper(scorer) if parallel else None
    try:
        t0 = time.perf_counter()
        with Progress(
            TextColumn("scoring"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            console=console,
            disable=not progress,
            transient=True,
        ) as bar:
            task = bar.add_task("score", total=len(files))
            if helper is not None:

                def taken() -> None:
                    """Files taken so far, by either process."""
                    bar.update(task, completed=min(helper.counter.value, len(files)))

                done = score_with_helper(helper, scorer, files, networks, reference_episodes, cache, taken, pictures)
            else:
                done = score_here(scorer, files, reference_episodes, cache, lambda: bar.advance(task))
        scored, recordings = done.scored, done.recordings
        normalise(scored, done.references)
        seconds["scoring"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        drawing = pictures and bool(scored)
        if drawing:  # the path and deviation figures need no report: they start first
            expert_cache = run / "assessment" / "expert_paths.npz" if run is not None else None
            by = group_key([row(s) for s in scored])
            seeds = [s.meta.get("seed", 0) for s in scored]
            compute = helper and helper.expert_paths
            devs = deviations(scored, expert_paths(scorer, seeds, expert_cache, compute, recordings))
            radius = scorer.spec.scene.radius
            early = _run(helper, draw_path_figures, scored, devs, by, paths, radius)
            seconds["pictures"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        report = build_report(scored, done.references, done.problems, done.learned)
        if recordings is not None:  # 1 is the recordings learned from, not the scripted expert
            report["normalisation"] = report["normalisation"].replace("scripted expert", "recordings learned from")
            report["warnings"] = [w.replace("scripted expert", "recordings learned from") for w in report["warnings"]]
        seconds["report"] = time.perf_counter() - t0
        report["seconds"] = seconds
        result = Assessment(report, {}, seconds)
        paths["json"].parent.mkdir(parents=True, exist_ok=True)
        paths["csv"].write_text(csv_text(report))
        result.files["csv"] = paths["csv"]
        if drawing:  # the distributions figure in the helper too while this process writes the recording
            from ..log.assessment import log_assessment

            t0 = time.perf_counter()
            late = _run(helper, plot_distributions, report, paths["distributions"])
            rid = recording_id or f"assessment-{scorer.spec.name}"
            rrd = log_assessment(paths["rrd"], rid, scorer.env.task, scored, report, devs, lambda s: group_of(s, by))
            result.files |= early.result() | {"distributions": late.result(), "rrd": rrd}
            seconds["pictures"] += time.perf_counter() - t0
    finally:
        if helper is not None:
            helper.close()
    paths["json"].write_text(json.dumps(report, indent=2, default=float))
    result.files["json"] = paths["json"]
    return result


def _run(helper: Helper | None, fn, *args) -> Future:
    """fn(*args) in the helper process, or here and now (a finished future)."""
    if helper is not None:
        return helper.submit(fn, *args)
    done: Future = Future()
    done.set_result(fn(*args))
    return done
