"""Where fastrl keeps what it makes once per machine (pose estimators, an ffmpeg link, line distances): stdlib only."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    """$FASTRL_CACHE, else $XDG_CACHE_HOME/fastrl, else ~/.cache/fastrl."""
    if os.environ.get("FASTRL_CACHE"):
        return Path(os.environ["FASTRL_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "fastrl"
