"""Objects that live through a long loop (libraries, models, envs) kept out of the collector's full passes."""

from __future__ import annotations

import atexit
import contextlib
import gc
from collections.abc import Iterator


@contextlib.contextmanager
def long_lived() -> Iterator[None]:
    """Within the block, the garbage collector skips everything alive at its start (gc.freeze): a full pass over
    hundreds of thousands of library objects cost 0.1-0.2 s each, several times a run. Not nested."""
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def no_collection_at_exit() -> None:
    """Let the interpreter's shutdown skip its full collections over every object still alive (0.15-0.2 s of a
    command's exit with torch or matplotlib loaded). Registered first, the freeze runs after every later atexit
    handler (Rerun's flush among them); what is freed by reference counting is freed as before."""
    atexit.register(gc.freeze)
