"""Scoring archives in bounded memory: which files are left to score (the journal has the rest), which few are
kept whole for the pictures, and every file's scalars read back in file order."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ...assess.journal import Journal, slim
from ...assess.scoring import TrajectoryScores

SAMPLE = 200  # beyond this many files, the paths, deviations and the recording draw this many of them


@dataclass
class Job:
    """The files of one `fastrl score`, the indices still to score, those kept whole, and the journal."""

    files: list[Path]
    todo: list[int]
    keep: set[int]
    journal: Journal
    streaming: bool  # more files than SAMPLE: keep only the sample whole


def sample_indices(n: int, k: int = SAMPLE) -> set[int]:
    """Every index below n if n <= k, else k of them evenly spaced from the first to the last (deterministic)."""
    if n <= k:
        return set(range(n))
    return {round(j * (n - 1) / (k - 1)) for j in range(k)}


def sample_note(drawn: int, of: int) -> str:
    """What the pictures show when they draw a sample."""
    return (
        f"the path and deviation figures and the recording's paths draw {drawn} of the {of} trajectories, evenly "
        "spaced in file order; the distributions, tables and rankings use every one"
    )


def plan_job(files: list[Path], journal: Journal, pictures: bool, fresh: bool, streaming: bool) -> Job:
    """Open the journal and list what to score: every file not journaled as it is now, and with `pictures` the
    sampled ones (their paths are not journaled)."""
    keep = sample_indices(len(files), SAMPLE if streaming else len(files)) if pictures else set()
    done = {} if fresh else journal.done(files)
    journal.open(fresh)
    todo = [i for i, f in enumerate(files) if str(f) not in done or i in keep]
    return Job(files, todo, keep, journal, streaming)


def gathered(journal: Journal, files: list[Path]) -> tuple[list[TrajectoryScores], list[str]]:
    """Every file's scores (without their arrays) and the problems, in file order, from the journal."""
    lines = journal.done(files)
    scored, problems = [], []
    for f in files:
        line = lines.get(str(f))
        if line is None:
            problems.append(f"{f}: changed while it was scored (or was not scored): score it again")
        elif "problem" in line:
            problems.append(line["problem"])
        else:
            scored.append(slim(line))
    return scored, problems
