"""A second process for `fastrl score`: it scores part of the files and draws the figures beside the recording."""

from __future__ import annotations

import multiprocessing
import os
import signal
from concurrent.futures import Future, ProcessPoolExecutor
from itertools import accumulate
from pathlib import Path

from ..assess.references import compute_expert_paths
from ..assess.report import score_files
from ..assess.scoring import Scorer

MIN_FILES = 16  # below this, forking costs more than it saves
# Scoring splits the bytes evenly: the figures can only start once both halves are in, and the worker's pyplot
# import (0.4 s) runs while this process merges, normalises and builds the report.
WORKER_SHARE = 0.5
_SCORER: Scorer | None = None  # the forked worker's copy of the parent's scorer


def _adopt(scorer: Scorer) -> None:
    """Worker start: keep the inherited scorer; Ctrl-C is the parent's to handle."""
    global _SCORER
    _SCORER = scorer
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _score(files: list[Path]):
    """Worker side of `Helper.score`."""
    return score_files(_SCORER, files)


def _expert(seeds: list[int]):
    """Worker side of `Helper.expert_paths`."""
    return compute_expert_paths(_SCORER, seeds)


def _warm() -> None:
    """Import pyplot while the parent finishes its share, so the figures start at once."""
    from ..assess.figures import _pyplot

    _pyplot()


def cores() -> int:
    """CPUs this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def split_by_size(files: list[Path], share: float = 0.5) -> int:
    """The index that cuts `files` so that the run before it holds about `share` of the bytes (missing files: 0)."""
    cum = list(accumulate((f.stat().st_size if f.is_file() else 0 for f in files), initial=0))
    return min(range(len(cum)), key=lambda k: abs(cum[k] - share * cum[-1]))


class Helper:
    """One forked worker that inherits the parent's scorer: only file names, results and figure data cross over."""

    def __init__(self, scorer: Scorer):
        fork = multiprocessing.get_context("fork")
        self.scorer = scorer
        self.pool = ProcessPoolExecutor(1, mp_context=fork, initializer=_adopt, initargs=(scorer,))

    @staticmethod
    def worth_it(n_files: int) -> bool:
        """Whether a second process pays: enough files, and a second core."""
        return n_files >= MIN_FILES and cores() > 1 and "fork" in multiprocessing.get_all_start_methods()

    def score(self, files: list[Path], warm: bool = True) -> Future:
        """Score `files` in the worker (a future of score_files' result); then, if `warm`, import pyplot there."""
        future = self.pool.submit(_score, files)
        if warm:
            self.pool.submit(_warm)
        return future

    def expert_paths(self, seeds: list[int]) -> dict:
        """The scripted expert's paths on `seeds`, the first half rolled out in the worker, the rest here."""
        half = len(seeds) // 2
        theirs = self.pool.submit(_expert, seeds[:half])
        mine = compute_expert_paths(self.scorer, seeds[half:])
        return theirs.result() | mine

    def submit(self, fn, *args) -> Future:
        """Run a picklable function in the worker."""
        return self.pool.submit(fn, *args)

    def close(self) -> None:
        """Stop the worker (pending work is cancelled)."""
        self.pool.shutdown(wait=True, cancel_futures=True)
