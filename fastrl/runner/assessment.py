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
from ..assess.references import expert_paths, reference_scores
from ..assess.report import build_report, csv_text, group_key, row, score_files, trajectory_files
from ..assess.scoring import Scorer, normalise
from ..data.recordings import load_recordings
from ..irl.networks import has_networks, load_networks
from ..log.assessment import log_assessment
from ..spec import load_spec
from .helper import WORKER_SHARE, Helper, split_by_size


@dataclass
class Assessment:
    """What one `fastrl score` produced: the report and the files written."""

    report: dict
    files: dict[str, Path] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)


def load_scorer(run: Path | None, spec_path: Path | None) -> tuple[Scorer, str | None]:
    """A scorer for a run (its spec and, after inverse RL, its learned networks) or for a bare spec."""
    if run is not None:
        if not (run / "spec.yaml").exists():
            raise FileNotFoundError(f"{run} is not a run directory (no spec.yaml)")
        networks = None
        if has_networks(run / "networks"):
            networks = load_networks(run / "networks")
        return Scorer(load_spec(run / "spec.yaml"), networks), run.name
    if spec_path is None:
        raise FileNotFoundError("give --run RUN_DIR (learned scores) or --spec SPEC (heuristic and kinematic only)")
    return Scorer(load_spec(spec_path)), None


def learned_from(scorer: Scorer) -> list | None:
    """The recordings a run learned from (its `irl.demonstrations.path`), best heuristic return first; None when
    it learned from the scripted expert or from nothing: then the scripted expert is the reference."""
    spec = scorer.spec
    folder = spec.irl.demonstrations.path
    if not scorer.learned or folder is None or not Path(folder).is_dir():
        return None
    recordings = [t for _, t in load_recordings([folder])[0]]
    if not recordings:
        return None
    heuristic = [scorer.score(t).scores["heuristic"] for t in recordings]
    return [recordings[i] for i in sorted(range(len(recordings)), key=lambda i: -heuristic[i])]


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
    t0 = time.perf_counter()
    scorer, recording_id = load_scorer(run, spec_path)
    paths, seconds = outputs_for(output, run), {"load": time.perf_counter() - t0}
    t0 = time.perf_counter()
    cache = run / "assessment" / "references.json" if run is not None else None
    recordings = learned_from(scorer)
    references = reference_scores(scorer, reference_episodes, cache, recordings)
    seconds["references"] = time.perf_counter() - t0
    files = trajectory_files(inputs)
    helper = Helper(scorer) if Helper.worth_it(len(files)) and parallel is not False or parallel else None
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
            cut = split_by_size(files, WORKER_SHARE) if helper else 0  # the worker: files[:cut]
            theirs = helper.score(files[:cut], warm=pictures) if helper else None
            scored, problems = score_files(scorer, files[cut:], on_file=lambda _f: bar.advance(task))
            if theirs is not None:
                first, first_problems = theirs.result()
                scored, problems = first + scored, first_problems + problems
                bar.advance(task, cut)
        normalise(scored, references)
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
        report = build_report(scored, references, problems, scorer.learned)
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
