"""The bundled task specs: package data (fastrl/specs/*.yaml) found through importlib.resources, by name."""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

# Installed packages are plain folders (a wheel unpacks; MuJoCo and the loader read real files), so a Path.
SPECS_DIR = Path(str(resources.files(__package__).joinpath("specs")))


def bundled_names() -> list[str]:
    """Names of the bundled specs (file names without .yaml), sorted."""
    return sorted(p.stem for p in SPECS_DIR.glob("*.yaml"))


def spec_path(name: str) -> Path:
    """Path of a bundled spec by name (e.g. 'tracelines'); FileNotFoundError lists the bundled names."""
    path = SPECS_DIR / f"{name}.yaml"
    if os.sep in name or "/" in name or not path.is_file():
        raise FileNotFoundError(f"no bundled spec '{name}' (bundled: {', '.join(bundled_names())})")
    return path


def find_spec(spec) -> Path:
    """The spec file as given if there is one (not a folder), else the bundled spec of that name, else the path."""
    path = Path(spec)
    if os.path.lexists(path) and not path.is_dir():  # runs/ holds a folder per spec name: `fastrl run tracelines`
        return path
    try:
        return spec_path(str(spec))
    except FileNotFoundError:
        return path


def missing_spec_message() -> str:
    """What to say when a spec is neither a file nor a bundled name."""
    return f"cannot read file: no such file, and no bundled spec of that name (bundled: {', '.join(bundled_names())})"
