"""The scripted expert's evaluation remembered on this machine: a pure function of the spec, its seeds and the code."""

from __future__ import annotations

import functools
import hashlib
import json
from pathlib import Path

from ...atomic import write_json
from ...cache import cache_dir

NOT_ITS = {"name", "description", "train", "irl", "study"}  # what the expert's episodes do not depend on
KEPT = 256  # memos kept, the newest: every edit of fastrl's sources makes new keys


@functools.cache
def code_digest() -> bytes:
    """SHA-256 of fastrl's own sources and the numerical libraries' versions: any edit makes new keys."""
    import mujoco
    import numpy
    import scipy

    root = Path(__file__).resolve().parents[2]
    h = hashlib.sha256(f"{mujoco.__version__} {numpy.__version__} {scipy.__version__}".encode())
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.digest()


def memo_path(spec, seeds: list[int]) -> Path:
    """Where the expert's evaluation of this spec on these seeds is kept."""
    what = {"spec": spec.model_dump(mode="json", exclude=NOT_ITS), "seeds": list(seeds)}
    h = hashlib.sha256(json.dumps(what, sort_keys=True, separators=(",", ":")).encode())
    h.update(code_digest())
    return cache_dir() / "expert" / f"{h.hexdigest()[:24]}.json"


def recall(spec, seeds: list[int]) -> dict | None:
    """The remembered evaluation, or None (never computed here, or its file unreadable)."""
    try:
        return json.loads(memo_path(spec, seeds).read_text())
    except (OSError, ValueError):
        return None


def remember(spec, seeds: list[int], summary: dict) -> None:
    """Keep the evaluation for the next run (quietly not, where the cache cannot be written)."""
    path = memo_path(spec, seeds)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_json(path, summary)
        memos = sorted(path.parent.glob("*.json"), key=lambda p: p.stat().st_mtime, reverse=True)
        for old in memos[KEPT:]:
            old.unlink(missing_ok=True)
    except OSError:
        pass
