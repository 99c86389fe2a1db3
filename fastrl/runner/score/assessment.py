"""The assessment stage: score trajectories with a run's learned networks, write JSON, CSV, PNG and Rerun."""

from __future__ import annotations

import json
import time
from concurrent.futures import Future
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console

from ...assess.figures import deviations, draw_path_figures, plot_distributions
from ...assess.journal import Journal, identity
from ...assess.references import expert_paths, references_for
from ...assess.report import SCORING_ERRORS, build_report, csv_text, group_key, problem_text, row, trajectory_files
from ...assess.scoring import Scorer, TrajectoryScores, normalise
from ...bundled import find_spec
from ...irl.network_files import has_networks
from ...spec import load_spec
from ..bars import counting_bar
from .archive import SAMPLE, Job, gathered, plan_job, sample_note
from .helper import Helper, journaling, record_assessment, score_shared
from .video_inputs import videos_as_trajectories


@dataclass
class Assessment:
    """What one `fastrl score` produced: the report and the files written."""

    report: dict
    files: dict[str, Path] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    resumed: int = 0  # files whose scores were read from the journal, not scored again


@dataclass
class Scored:
    """The trajectories kept whole for the pictures (by file index) and what normalises the scores; every file's
    scalars and problems are in the journal."""

    kept: dict[int, TrajectoryScores]
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
            from ...irl.networks import load_networks

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
        "journal": parent / f"{stem}.journal.jsonl",
        "videos": parent / f"{stem}_from_video",
    }


def score_here(scorer: Scorer, job: Job, episodes: int, cache: Path | None, on_file) -> Scored:
    """Score every file to do in this process."""
    references, recordings = references_for(scorer, episodes, cache)
    sink = journaling(job.journal, job.files, job.keep)
    kept = {}
    for i in job.todo:
        try:
            entry = (i, scorer.score_file(job.files[i]), None)
        except SCORING_ERRORS as e:
            entry = (i, None, problem_text(job.files[i], e))
        if sink(*entry):
            kept[i] = entry[1]
        on_file()
    return Scored({i: s for i, s in kept.items() if s is not None}, references, recordings, scorer.learned)


def score_with_helper(
    helper: Helper, scorer: Scorer, job: Job, episodes: int, cache: Path | None, on_file, pictures: bool
) -> Scored:
    """Score in two processes taking files from one counter; each journals what it scores. The worker (forked with
    the scorer and its networks) first loads or computes the references, then scores.

    With `pictures`, each process first imports what it will draw with (matplotlib and Rerun there, matplotlib here):
    the counter shares out the files, so time spent importing now is made up by the other process scoring more."""
    prepared = helper.prepare(episodes, cache, pictures)
    todo = [job.files[i] for i in job.todo]
    keep = {k for k, i in enumerate(job.todo) if i in job.keep}
    theirs = helper.score_share(todo, Journal(path=job.journal.path, identity=job.journal.identity), keep)
    if pictures:  # this process draws the distributions
        from ...assess.figures import _pyplot

        _pyplot()

    def after_file() -> bool:
        """Show progress; stop early if the worker could not prepare the references."""
        on_file()
        return prepared.done() and prepared.exception() is not None

    mine = score_shared(todo, helper.counter, scorer.score_file, after_file, journaling(job.journal, todo, keep))
    references, recordings = prepared.result()  # the worker's error, if any, is raised here
    kept = {job.todo[i]: s for i, s, _ in mine + theirs.result() if s is not None}
    return Scored(kept, references, recordings, scorer.learned)


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
    address: str | None = None,
    fresh: bool = False,
) -> Assessment:
    """Score every trajectory file under `inputs` and write the report and its pictures.

    `parallel`: score and draw in a second, forked process (None: when there are enough files and a second core).
    `address`: score on Ray instead ("local" starts one here). Each file scored is journaled beside the report: a
    rerun skips those journaled with the same size and time (`fresh`: none). Beyond SAMPLE files, only a sample
    of them is kept whole for the pictures, the rest as scalars."""
    console = console or Console(stderr=True)
    t0 = time.perf_counter()
    spec_path = None if spec_path is None else find_spec(spec_path)  # a bundled spec's name, as elsewhere
    scorer, recording_id = load_scorer(run, spec_path)
    paths, seconds = outputs_for(output, run), {"load": time.perf_counter() - t0}
    places = [run, run.parent] if run is not None else []
    inputs, videos, _ = videos_as_trajectories(
        inputs, scorer.spec, paths["videos"], places=places, console=console, progress=progress
    )
    if videos.written or videos.errors:
        seconds["videos"] = videos.seconds
    files = trajectory_files(inputs)
    streaming = len(files) > SAMPLE
    parallel = address is None and (Helper.worth_it(len(files)) if parallel is None else parallel)
    networks = run / "networks" if run is not None and has_networks(run / "networks") else None
    cache = run / "assessment" / "references.json" if run is not None else None
    journal = Journal(path=paths["journal"], identity=identity(run / "spec.yaml" if run else spec_path, networks))
    job = plan_job(files, journal, pictures, fresh, streaming)
    for note in journal.notes:
        console.print(f"note: {note}", markup=False, highlight=False)
    if len(job.todo) < len(files):
        console.print(
            f"resuming: {len(files) - len(job.todo)} of {len(files)} files already scored in {journal.path}",
            markup=False,
            highlight=False,
        )
    helper = Helper(scorer) if parallel else None
    try:
        t0 = time.perf_counter()
        with counting_bar(console, progress, "scoring") as bar:
            task = bar.add_task("score", total=len(job.todo))
            if address is not None:
                from .ray_scoring import score_on_ray

                done = score_on_ray(
                    address, scorer, run, spec_path, job, reference_episodes, cache, lambda: bar.advance(task)
                )
            elif helper is not None:

                def taken() -> None:
                    """Files taken so far, by either process."""
                    bar.update(task, completed=min(helper.counter.value, len(job.todo)))

                done = score_with_helper(helper, scorer, job, reference_episodes, cache, taken, pictures)
            else:
                done = score_here(scorer, job, reference_episodes, cache, lambda: bar.advance(task))
        journal.close()
        everything, problems = gathered(journal, files)
        kept = [done.kept[i] for i in sorted(done.kept)]
        recordings = done.recordings
        normalise(everything, done.references)
        normalise(kept, done.references)
        seconds["scoring"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        drawing = pictures and bool(kept)
        if drawing:  # the path and deviation figures need no report: they start first
            expert_cache = run / "assessment" / "expert_paths.npz" if run is not None else None
            by = group_key([row(s) for s in everything])
            seeds = [s.seed for s in kept]
            compute = helper and helper.expert_paths
            devs = deviations(kept, expert_paths(scorer, seeds, expert_cache, compute, recordings))
            radius = scorer.spec.scene.radius
            early = _run(helper, draw_path_figures, kept, devs, by, paths, radius)
            seconds["pictures"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        report = build_report(everything, done.references, videos.errors + problems, done.learned)
        if recordings is not None:  # 1 is the recordings learned from, not the scripted expert
            report["normalisation"] = report["normalisation"].replace("scripted expert", "recordings learned from")
            report["warnings"] = [w.replace("scripted expert", "recordings learned from") for w in report["warnings"]]
        if drawing and len(kept) < len(everything):
            report["pictures_sample"] = sample_note(len(kept), len(everything))
        seconds["report"] = time.perf_counter() - t0
        report["seconds"] = seconds
        result = Assessment(report, {}, seconds, resumed=len(files) - len(job.todo))
        paths["json"].parent.mkdir(parents=True, exist_ok=True)
        paths["csv"].write_text(csv_text(report))
        result.files["csv"] = paths["csv"]
        if drawing:  # the recording in the helper, after the path figures, while this process draws the distributions
            t0 = time.perf_counter()
            rid = recording_id or f"assessment-{scorer.spec.name}"
            recorded = (paths["rrd"], rid, kept, report, devs, by)
            rrd = helper.record(*recorded) if helper else _run(None, record_assessment, scorer.env.task, *recorded)
            distributions = plot_distributions(report, paths["distributions"])
            result.files |= early.result() | {"distributions": distributions, "rrd": rrd.result()}
            seconds["pictures"] += time.perf_counter() - t0
    finally:
        if helper is not None:
            helper.close()
        journal.close()
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
