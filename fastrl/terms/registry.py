"""Name -> pure function registries for reward features and observation terms."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Term:
    """A registered pure function of the task state and its declared parameters."""

    name: str
    fn: Callable[..., Any]
    params: dict[str, inspect.Parameter]
    doc: str
    size: int = 1
    needs: tuple[str, ...] = ()
    per: str = ""  # "instrument": size values per instrument; "coordinate": one per instrument coordinate

    def width(self, coordinates: list[int]) -> int:
        """Values the term gives for instruments with these coordinate counts (spec order)."""
        if self.per == "instrument":
            return self.size * len(coordinates)
        if self.per == "coordinate":
            return sum(coordinates)
        return self.size

    def check_params(self, given: dict[str, Any]) -> list[tuple[str, str]]:
        """Return (param, problem) pairs for parameters the function does not take or mistypes."""
        problems = []
        for key, value in given.items():
            if key not in self.params:
                known = ", ".join(self.params) or "none"
                problems.append((key, f"'{self.name}' takes no parameter '{key}' (it takes: {known})"))
                continue
            default = self.params[key].default
            if isinstance(default, (int, float)) and not isinstance(default, bool):
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    problems.append((key, f"must be a number, got {value!r}"))
        return problems


class Registry(dict):
    """A dict of Terms with a decorator to add to it."""

    def __init__(self, kind: str):
        super().__init__()
        self.kind = kind

    def register(self, fn=None, *, size: int = 1, needs: tuple[str, ...] = (), per: str = ""):
        """Register `fn` under its own name; the first argument is the task state."""

        def add(f):
            sig = list(inspect.signature(f).parameters.values())[1:]
            doc = (f.__doc__ or "").strip().splitlines()[0] if f.__doc__ else ""
            self[f.__name__] = Term(f.__name__, f, {p.name: p for p in sig}, doc, size, needs, per)
            return f

        return add(fn) if fn is not None else add


REWARD_FEATURES = Registry("reward feature")
OBSERVATION_TERMS = Registry("observation term")
