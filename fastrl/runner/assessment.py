"""The assessment stage: score trajectories with a run's learned networks, write JSON, CSV, PNG and Rerun."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ..assess.figures import deviations, group_of, plot_deviation, plot_distributions, plot_paths
from ..assess.references import expert_paths, reference_scores
from ..assess.report import build_report, csv_text, score_files, trajectory_files
from ..assess.scoring import Scorer, normalise
from ..data.recordings import load_recordings
from ..irl.networks import has_networks, load_networks
from ..log.assessment import log_assessment
from ..spec import load_spec


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
) -> Assessment:
    """Score every trajectory file under `inputs` and write the report and its pictures."""
    console = console or Console(stderr=True)
    scorer, recording_id = load_scorer(run, spec_path)
    paths, seconds = outputs_for(output, run), {}
    t0 = time.perf_counter()
    cache = run / "assessment" / "references.json" if run is not None else None
    recordings = learned_from(scorer)
    references = reference_scores(scorer, reference_episodes, cache, recordings)
    seconds["references"] = time.perf_counter() - t0
    files = trajectory_files(inputs)
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
        scored, problems = score_files(scorer, files, on_file=lambda _f: bar.advance(task))
    normalise(scored, references)
    seconds["scoring"] = time.perf_counter() - t0
    report = build_report(scored, references, problems, scorer.learned)
    if recordings is not None:  # 1 is the recordings learned from, not the scripted expert
        report["normalisation"] = report["normalisation"].replace("scripted expert", "recordings learned from")
        report["warnings"] = [w.replace("scripted expert", "recordings learned from") for w in report["warnings"]]
    report["seconds"] = seconds
    result = Assessment(report, {}, seconds)
    paths["json"].parent.mkdir(parents=True, exist_ok=True)
    paths["csv"].write_text(csv_text(report))
    result.files["csv"] = paths["csv"]
    if pictures and scored:
        t0 = time.perf_counter()
        rid = recording_id or f"assessment-{scorer.spec.name}"
        _pictures(scorer, scored, report, paths, rid, result, recordings)
        seconds["pictures"] = time.perf_counter() - t0
    paths["json"].write_text(json.dumps(report, indent=2, default=float))
    result.files["json"] = paths["json"]
    return result


def _pictures(
    scorer: Scorer,
    scored,
    report: dict,
    paths: dict[str, Path],
    recording_id: str,
    result: Assessment,
    recordings: list | None = None,
) -> None:
    """PNG figures and the Rerun recording of the assessment."""
    by = report["grouped_by"]
    devs = deviations(scored, expert_paths(scorer, [s.meta.get("seed", 0) for s in scored], recordings))
    result.files["paths"] = plot_paths(scored, by, paths["paths"], scorer.spec.scene.radius)
    result.files["deviation"] = plot_deviation(scored, devs, by, paths["deviation"])
    result.files["distributions"] = plot_distributions(report, paths["distributions"])
    result.files["rrd"] = log_assessment(
        paths["rrd"], recording_id, scorer.env.task, scored, report, devs, lambda s: group_of(s, by)
    )
