"""The paper's protocol on recordings (`fastrl assess`): rank every trajectory, learn reward, value and policy from
the best K without their actions, score them all, and keep the learned networks for `fastrl score --run`."""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console

from ..assess.report import csv_text
from ..atomic import write_text
from ..spec import load_spec
from .chosen import (
    BY,
    DEFAULT_BY,
    criterion,
    nothing_there,
    rank_recordings,
    write_demonstrations,
)
from .runs.rundir import latest_checkpoint, new_run_dir, update_meta, write_meta
from .runs.runfiles import read_meta
from .runs.stops import signal_name
from .score.assessment import Assessment, assess, outputs_for
from .score.video_inputs import video_files, video_overrides, videos_as_trajectories
from .seeds_at_once import at_once, learn_at_once

ALGORITHMS = ("airl", "gail")
# the learned policy's final evaluation: no scripted expert beside it (nothing on this path consults one) and
# endoscope images for 2 of its episodes, not 20 (they took 12 s and 9 s of TraceLines' 2 min); --set overrides
EVALUATION = ("evaluate.expert=false", "evaluate.record_episodes=2")


class ScoringInterrupted(Exception):
    """Ctrl-C while the learned networks scored the recordings: they are kept in `run`, to resume."""

    def __init__(self, run: Path, signal_name: str = "SIGINT"):
        self.run, self.signal_name = run, signal_name
        super().__init__(f"{signal_name}: scoring stopped; the learned networks are kept in {run}")


@dataclass
class Protocol:
    """What one `fastrl assess` did: where, from which recordings it learned (one run per seed) and why, what it
    skipped."""

    run: Path
    learned: list[Path]
    chosen: list[dict]
    why: str
    assessment: Assessment
    skipped: list[str] = field(default_factory=list)


def run_protocol(
    inputs: list[Path],
    spec_path: Path,
    top: int,
    by: str = DEFAULT_BY,
    algorithm: str = "airl",
    overrides=(),
    root: Path = Path("runs"),
    output: Path | None = None,
    console: Console | None = None,
    progress: bool = True,
    pictures: bool = True,
    keep_actions: bool = False,
    seeds: int = 1,
    address: str | None = None,
    resuming: Path | None = None,
) -> Protocol:
    """Rank, choose the best `top`, learn from them without actions on `seeds` training seeds (the spec's and the
    next ones; as Ray tasks at `address`, all at once where it has the CPUs; else at once on this machine's spare
    cores), score everything; return what was done. `keep_actions` (bench/learn_from_people.py's comparison) learns
    from the recorded actions where there are. `resuming`: a stopped assessment's folder, continued (resume_protocol).
    """
    from .train.run import learn_into

    console = console or Console(stderr=True)
    if by not in BY:
        raise ValueError(f"--by must be one of {', '.join(BY)}, got {by!r}")
    if algorithm not in ALGORITHMS:
        raise ValueError(f"--algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
    if top < 1:
        raise ValueError(f"--top must be at least 1, got {top}")
    if seeds < 1:
        raise ValueError(f"--seeds must be at least 1, got {seeds}")
    spec = load_spec(spec_path, overrides)
    run, skipped = None, []
    if video_files(inputs)[0]:  # poses read off videos are coarser: the cue's centring tolerance widens with them
        recorded, overrides = spec, [*overrides, *video_overrides(spec)]
        spec = load_spec(spec_path, overrides)
        run, inputs, skipped = _from_videos(inputs, spec, recorded, root, algorithm, console, progress)
    ranked, unusable = rank_recordings(spec, inputs, by, top)
    skipped += unusable
    if not ranked:
        if run is not None:  # only the unusable videos' poses were written: nothing to keep
            shutil.rmtree(run)
        if not skipped:
            raise FileNotFoundError(nothing_there(inputs))
        first = f"; {len(skipped)} skipped, the first: {skipped[0]}"
        raise FileNotFoundError(f"no recording could be read and replayed: nothing to learn from{first}")
    chosen = ranked[:top]
    if resuming is None:
        run = run or new_run_dir(Path(root), spec, label=f"assess-{algorithm}-s{spec.train.seed}")
        command = {
            "spec": str(Path(spec_path).resolve()),
            "inputs": [str(Path(p).resolve()) for p in inputs],
            **{"top": top, "by": by, "algorithm": algorithm, "seeds": seeds, "keep_actions": keep_actions},
            **{"output": str(output.resolve()) if output else None, "pictures": pictures},
        }
        extra = {"status": "learning", "overrides": list(overrides), "kind": "assess", "assess": command}
        write_meta(run, spec, str(spec_path), extra)
        write_demonstrations(run, spec, ranked, top, inputs, keep_actions)
    else:  # its best and others as written when it began, whatever the spec file says now
        run = resuming
        update_meta(run, status="learning")
    if (run / "others").is_dir():
        overrides = [*overrides, f"irl.demonstrations.others={run / 'others'}"]
    rows = [{"file": s.name, "subject": s.subject, "skill": s.skill, **criterion(s)} for s, _ in chosen]
    why = (
        f"learned from the {len(chosen)} best of {len(ranked)} recordings by {BY[by]}"
        + (f" (the next best: {ranked[top][0].name})" if len(ranked) > top else " (all of them)")
        + ("; their recorded actions kept" if keep_actions else "; their actions dropped, recovered from their states")
    )
    console.print(why, markup=False, highlight=False)
    trained = [spec.train.seed + i for i in range(seeds)]
    learning = [
        (
            [
                *EVALUATION,
                *overrides,
                f"irl.algorithm={algorithm}",
                f"irl.demonstrations.path={run / 'best'}",
                "study.enabled=false",
                *([f"train.seed={seed}"] if seeds > 1 else []),
            ],
            run / ("learned" if seeds == 1 else f"learned-s{seed}"),
        )
        for seed in trained
    ]
    if resuming is not None:
        for _, into in learning:
            console.print(f"{into.name}: {_where(into)}", markup=False, highlight=False)
    if address is not None:
        from .seeds_on_ray import learn_on_ray

        learned = learn_on_ray(address, spec_path, learning, console)
    elif (processes := at_once(seeds)) > 1:  # spare cores
        learned = learn_at_once(spec_path, learning, console, processes, progress)
    else:
        learned = [learn_into(spec_path, o, into, console=console, progress=progress) for o, into in learning]
    update_meta(run, status="scoring")
    scores = output or run / "scores.json"
    try:
        if seeds == 1:
            result = assess(
                list(inputs), run=learned[0], output=scores, console=console, progress=progress, pictures=pictures
            )
        else:
            result = assess_seeds(inputs, learned, trained, scores, console, progress, pictures)
    except KeyboardInterrupt as stop:
        raise ScoringInterrupted(run, signal_name(stop)) from None
    summary = {
        "spec": spec.name,
        "by": by,
        "rule": BY[by],
        "top": top,
        "algorithm": algorithm,
        "why": why,
        "chosen": rows,
        "order": [s.name for s, _ in ranked],
        "skipped": skipped,
        "learned": [str(p) for p in learned],
        "scores": {k: str(v) for k, v in result.files.items()},
    }
    write_text(run / "protocol.json", json.dumps(summary, indent=2, default=float))
    update_meta(run, status="done")
    return Protocol(run, learned, rows, why, result, skipped)


def resume_protocol(run: Path, console: Console | None = None, progress: bool = True, address=None) -> Protocol:
    """Continue a stopped `fastrl assess` in its folder with its own inputs and options: each seed learned is kept,
    each begun resumes from its checkpoint, the rest start; then everything is scored."""
    run = Path(run)
    meta = read_meta(run)
    command = meta.get("assess")
    if command is None:
        raise ValueError(f"{run} was not made by fastrl assess (its meta.json names no assessment): nothing to resume")
    return run_protocol(
        [Path(p) for p in command["inputs"]],
        Path(command["spec"]),
        command["top"],
        command["by"],
        command["algorithm"],
        meta.get("overrides", []),
        run.parent,
        Path(command["output"]) if command["output"] else None,
        console=console,
        progress=progress,
        pictures=command["pictures"],
        keep_actions=command["keep_actions"],
        seeds=command["seeds"],
        address=address,
        resuming=run,
    )


def _where(into: Path) -> str:
    """How far a seed's run in `into` got: what resuming does with it."""
    if not into.exists():
        return "starts"
    if read_meta(into).get("status") == "done":
        return "learned, kept"
    checkpoint = latest_checkpoint(into)
    return f"resumes from {int(checkpoint.name)} timesteps" if checkpoint else "starts again (no checkpoint)"


def assess_seeds(
    inputs, learned: list[Path], seeds: list[int], output: Path, console, progress, pictures
) -> Assessment:
    """Score every file with each seed's networks (reports under SEEDS/sN/ beside `output`), then as one: mean and
    spread per trajectory, the seeds' agreement and the warnings (fastrl.assess.agreement)."""
    from ..assess.agreement import combine

    reports = []
    for seed, run in zip(seeds, learned):
        one = assess(
            list(inputs),
            run=run,
            output=output.parent / "seeds" / f"s{seed}" / output.name,
            console=console,
            progress=progress,
            pictures=False,
        )
        reports.append(one.report)
    report = combine(reports, seeds)
    files = outputs_for(output, None)
    output.parent.mkdir(parents=True, exist_ok=True)
    write_text(files["csv"], csv_text(report))
    done = Assessment(report, {"csv": files["csv"]})
    if pictures:
        from ..assess.figures import plot_distributions
        from ..log.assessment import log_summary

        done.files["distributions"] = plot_distributions(report, files["distributions"])
        done.files["rrd"] = log_summary(files["rrd"], f"assessment-seeds-{seeds[0]}", report)
    write_text(files["json"], json.dumps(report, indent=2, default=float))
    done.files["json"] = files["json"]
    return done


def _from_videos(inputs, spec, recorded, root: Path, algorithm: str, console: Console, progress: bool):
    """(the run folder, the inputs, skipped videos): the run starts here and holds the videos' estimated trajectories
    (from_video/) and the pose estimator that read them; `recorded` is the spec before the video's overrides."""
    run = new_run_dir(Path(root), spec, label=f"assess-{algorithm}-s{spec.train.seed}")
    inputs, batch, source = videos_as_trajectories(
        inputs, spec, run / "from_video", recorded=recorded, console=console, progress=progress
    )
    shutil.copy2(source, run / source.name)  # `fastrl score --run RUN/learned VIDEOS` reads with the same estimator
    return run, inputs, batch.errors
