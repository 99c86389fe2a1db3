"""The distribution: its name on PyPI and its version (installed metadata, else the source tree's)."""

from __future__ import annotations

from importlib import metadata

DISTRIBUTION = "fastrl-surgery"  # pyproject's `name`; PyPI's `fastrl` is an unrelated project that imports as fastrl
VERSION = "0.3.0"  # pyproject's `version`: what a source tree without installed metadata reports


def installed_version() -> str | None:
    """The installed version of this distribution (never of another `fastrl`), or None when not installed."""
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return None


def version_line() -> str:
    """`fastrl --version`: distribution name and version, and the import name."""
    version = installed_version()
    where = "" if version is not None else ", source tree without installed metadata"
    return f"{DISTRIBUTION} {version or VERSION} (import name fastrl{where})"
