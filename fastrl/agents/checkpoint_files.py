"""Whether a checkpoint directory is whole, and the errors of a bad one, without torch (`fastrl score` checks runs)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path


class CheckpointMismatch(ValueError):
    """A checkpoint whose tensors do not fit the model the run's spec builds."""


class CheckpointDamaged(ValueError):
    """A checkpoint directory with missing, torn or damaged files."""


def file_sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def checkpoint_problem(path: Path) -> str | None:
    """Why a checkpoint directory cannot be loaded (missing, torn or damaged files), or None if it is whole."""
    path = Path(path)
    try:
        state = json.loads((path / "state.json").read_text())
    except FileNotFoundError:
        return "no state.json (it was being written when the run stopped)"
    except (OSError, ValueError) as e:
        return f"state.json does not parse ({e})"
    if not isinstance(state, dict) or not isinstance(state.get("timesteps"), int):
        return "state.json has no timesteps"
    files = state.get("files")
    if not isinstance(files, dict):  # written before checkpoints listed their files: try loading the weights
        import torch

        try:
            torch.load(path / "weights.pt", map_location="cpu", weights_only=True)
        except Exception as e:  # any failure to load means the checkpoint is unusable
            return f"weights.pt does not load ({str(e).splitlines()[0] if str(e) else type(e).__name__})"
        return None
    if "weights.pt" not in files:
        return "state.json lists no weights.pt"
    for name, digest in files.items():
        f = path / name
        if not f.is_file():
            return f"{name} is missing"
        if file_sha256(f) != digest:
            return f"{name} is damaged (its sha256 differs from the one in state.json)"
    return None
