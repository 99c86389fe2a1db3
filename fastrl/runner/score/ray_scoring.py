"""`fastrl score --address`: the files shared out in small batches over Ray actors (one per CPU of the cluster),
each holding a scorer; results stream back into this process's journal as each batch finishes."""

from __future__ import annotations

import os
from pathlib import Path

from ...assess.journal import record
from ...assess.references import references_for
from ...assess.report import SCORING_ERRORS, problem_text
from ...assess.scoring import Scorer

BATCH = 8  # files per Ray call: small, so a stop loses little and results stream


class RayScorer:
    """A Ray actor: the run's (or spec's) scorer, loaded once, scoring batches of files."""

    def __init__(self, run: str | None, spec: str | None):
        from .assessment import load_scorer

        self.scorer = load_scorer(Path(run) if run else None, Path(spec) if spec else None)[0]

    def score(self, batch: list[tuple[int, str, bool]]) -> list[tuple[int, dict, object]]:
        """(index, journal line, the scores kept whole or None) for each (index, file, keep whole) of a batch."""
        out = []
        for i, f, whole in batch:
            try:
                s = self.scorer.score_file(Path(f))
                out.append((i, record(Path(f), s), s if whole else None))
            except SCORING_ERRORS as e:
                out.append((i, record(Path(f), problem=problem_text(Path(f), e)), None))
        return out


def connect(address: str) -> bool:
    """Join the Ray cluster at `address`, or start a local Ray for "local"; whether this call connected."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    try:
        import ray
    except ImportError:
        raise ValueError("--address needs Ray: pip install 'fastrl-surgery[sweep]'") from None
    if ray.is_initialized():
        return False
    if address == "local":  # on loopback only (else Ray picks the machine's network address)
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
        cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
        ray.init(num_cpus=cpus, include_dashboard=False, log_to_driver=False, logging_level="WARNING")
    else:
        ray.init(address=address, log_to_driver=False, logging_level="WARNING")
    return True


def score_on_ray(address: str, scorer: Scorer, run: Path | None, spec: Path | None, job, episodes: int, cache, on_file):
    """Score the job's files on Ray; the references here meanwhile. Paths must be the same on every node."""
    import ray
    from ray.util import ActorPool

    from .assessment import Scored

    connected = connect(address)
    try:
        cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))
        actor = ray.remote(num_cpus=1)(RayScorer)
        where = (str(Path(run).resolve()) if run else None, str(Path(spec).resolve()) if spec else None)
        pool = ActorPool([actor.remote(*where) for _ in range(min(cpus, max(1, len(job.todo) // BATCH)))])
        batches = [
            [(i, str(Path(job.files[i]).resolve()), i in job.keep) for i in job.todo[k : k + BATCH]]
            for k in range(0, len(job.todo), BATCH)
        ]
        kept = {}
        results = pool.map_unordered(lambda a, b: a.score.remote(b), batches)
        references, recordings = references_for(scorer, episodes, cache)
        for batch in results:
            for i, line, whole in batch:
                job.journal.append(line | {"file": str(job.files[i])})
                if whole is not None:
                    kept[i] = whole
                on_file()
        return Scored(kept, references, recordings, scorer.learned)
    finally:
        if connected:
            ray.shutdown()
