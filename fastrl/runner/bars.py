"""The progress bar of the runner's long loops: what it does, a count of done and total, the time so far."""

from __future__ import annotations

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn


def counting_bar(console: Console, progress: bool, label: str = "{task.description}") -> Progress:
    """A transient bar that counts items (off where `progress` is false)."""
    return Progress(
        TextColumn(label),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        disable=not progress,
        transient=True,
    )
