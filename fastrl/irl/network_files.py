"""Whether a folder holds exported networks, answered without importing torch (scoring forks before it does)."""

from __future__ import annotations

from pathlib import Path


def has_networks(directory: Path) -> bool:
    """Whether a folder holds exported networks (a policy)."""
    return (Path(directory) / "policy.safetensors").is_file()
