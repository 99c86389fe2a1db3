"""A second process for `fastrl score`, forked with the scorer and its networks: it loads the references, scores files
taken from a counter shared with this process, then draws the path figures and writes the recording while this
process writes the report and draws the distributions."""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import Future
from pathlib import Path

from ...assess.journal import Journal, record
from ...assess.references import compute_expert_paths, references_for
from ...assess.report import SCORING_ERRORS, problem_text
from ...assess.scoring import Scorer
from ...forked import Worker, can_fork, context

MIN_FILES = 16  # below this, forking costs more than it saves
_SCORER: Scorer | None = None  # the forked worker's copy of the parent's scorer
_NEXT = None  # the worker's handle on the shared counter
_PARENT: int | None = None  # the parent's pid: if it dies (a kill), the worker stops taking files


def _adopt(scorer: Scorer, counter) -> None:
    """Worker start (after forked's signal setup: Ctrl-C is the parent's): keep the inherited scorer and counter."""
    global _SCORER, _NEXT, _PARENT
    _SCORER, _NEXT, _PARENT = scorer, counter, os.getppid()


def _prepare(episodes: int, cache: Path | None, pictures: bool) -> tuple:
    """Worker side of `Helper.prepare`."""
    prepared = references_for(_SCORER, episodes, cache)
    if pictures:  # import matplotlib and Rerun now: the files are shared out, so the parent scores more meanwhile
        from ...assess.figures import _pyplot
        from ...log import assessment  # noqa: F401

        _pyplot()
    return prepared


def _score_share(files: list[Path], journal: Journal | None = None, keep: set[int] | None = None) -> list[tuple]:
    """Worker side of `Helper.score_share`."""
    if journal is None:
        return score_shared(files, _NEXT, _SCORER.score_file)
    journal.open()
    try:
        return score_shared(files, _NEXT, _SCORER.score_file, orphaned, journaling(journal, files, keep))
    finally:
        journal.close()
        if orphaned():  # no one will read the result, and the pool's queue would keep this process waiting
            os._exit(0)


def _record(*args) -> Path:
    """Worker side of `Helper.record`."""
    return record_assessment(_SCORER.env.task, *args)


def record_assessment(task, path: Path, recording_id: str, kept: list, report: dict, devs: dict, by: str) -> Path:
    """The assessment's Rerun recording (paths by learned value, deviations, the report's tables)."""
    from ...assess.figures import group_of
    from ...log.assessment import log_assessment

    return log_assessment(path, recording_id, task, kept, report, devs, lambda s: group_of(s, by))


def _expert(seeds: list[int]):
    """Worker side of `Helper.expert_paths`."""
    return compute_expert_paths(_SCORER, seeds)


def orphaned() -> bool:
    """Whether the worker's parent has died (killed): then it stops after the file in hand, which is journaled."""
    return os.getppid() != _PARENT


def take(counter) -> int:
    """The index of the next file to score, from the counter both processes share."""
    with counter.get_lock():
        index = counter.value
        counter.value += 1
    return index


def score_shared(
    files: list[Path],
    counter,
    score: Callable,
    on_file: Callable[[], bool] | None = None,
    sink: Callable[[int, object, str | None], bool] | None = None,
) -> list[tuple[int, object, str | None]]:
    """(index, score(file), None), or (index, None, the problem), for each file taken from `counter` until none is
    left; `on_file()` after each file may return True to stop early. With `sink`, each entry goes to it first and
    only those it returns True for are listed (the rest are not kept)."""
    out = []
    while (i := take(counter)) < len(files):
        try:
            entry = (i, score(files[i]), None)
        except SCORING_ERRORS as e:
            entry = (i, None, problem_text(files[i], e))
        if sink is None or sink(*entry):
            out.append(entry)
        if on_file is not None and on_file():
            break
    return out


def journaling(journal: Journal, files: list[Path], keep: set[int] | None) -> Callable[[int, object, str | None], bool]:
    """A score_shared sink that journals each file's scores (or problem) and keeps the entries indexed in `keep`."""

    def sink(i: int, scored, problem: str | None) -> bool:
        """Journal one entry; whether to keep it."""
        journal.append(record(files[i], scored, problem))
        return keep is None or i in keep

    return sink


def cores() -> int:
    """CPUs this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


class Helper:
    """One forked worker that inherits the parent's scorer and its networks; only file names, results and figure
    data cross over."""

    def __init__(self, scorer: Scorer):
        self.scorer = scorer
        self.counter = context().Value("q", 0)
        # orphan_exit: a killed parent may leave the worker idle between two tasks, where it would wait for ever
        self.pool = Worker(initializer=_adopt, initargs=(scorer, self.counter), orphan_exit=True)

    @staticmethod
    def worth_it(n_files: int) -> bool:
        """Whether a second process pays: enough files, and a second core."""
        return n_files >= MIN_FILES and cores() > 1 and can_fork()

    def prepare(self, episodes: int, cache: Path | None, pictures: bool = False) -> Future:
        """Load (or compute) the references in the worker, and matplotlib if `pictures`; a future of (references,
        recordings learned from) as `references_for` gives them."""
        return self.pool.submit(_prepare, episodes, cache, pictures)

    def score_share(self, files: list[Path], journal: Journal | None = None, keep: set[int] | None = None) -> Future:
        """Score files taken from the shared counter in the worker, with the learned scores; a future of
        score_shared's list (with `journal`, each file is journaled there and only the indices in `keep` listed)."""
        return self.pool.submit(_score_share, files, journal, keep)

    def expert_paths(self, seeds: list[int]) -> dict:
        """The scripted expert's paths on `seeds`, the first half rolled out in the worker, the rest here."""
        half = len(seeds) // 2
        theirs = self.pool.submit(_expert, seeds[:half])
        mine = compute_expert_paths(self.scorer, seeds[half:])
        return theirs.result() | mine

    def record(self, path: Path, recording_id: str, kept: list, report: dict, devs: dict, by: str) -> Future:
        """A future of the recording written by `record_assessment` in the worker (after what it was given before)."""
        return self.pool.submit(_record, path, recording_id, kept, report, devs, by)

    def submit(self, fn, *args) -> Future:
        """Run a picklable function in the worker."""
        return self.pool.submit(fn, *args)

    def close(self) -> None:
        """Stop the worker (pending work is cancelled, no further file is taken)."""
        with self.counter.get_lock():
            self.counter.value = 2**62
        self.pool.shutdown()
