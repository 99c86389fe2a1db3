"""Name -> function registries for reward features, observation terms, and reset and termination terms."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from .domain import Domain


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
    domains: dict[str, Domain] = field(default_factory=dict)  # each parameter's allowed values, from registration

    def width(self, coordinates: list[int]) -> int:
        """Values the term gives for instruments with these coordinate counts (spec order)."""
        if self.per == "instrument":
            return self.size * len(coordinates)
        if self.per == "coordinate":
            return sum(coordinates)
        return self.size

    def check_params(self, given: dict[str, Any]) -> list[tuple[str, str]]:
        """(param, problem) pairs for parameters the function does not take or whose values leave their domain."""
        problems = []
        for key, value in given.items():
            if key not in self.params:
                known = ", ".join(self.params) or "none"
                problems.append((key, f"'{self.name}' takes no parameter '{key}' (it takes: {known})"))
            elif problem := self.domains[key].problem(value):
                problems.append((key, problem))
        return problems


class Registry(dict):
    """A dict of Terms with a decorator to add to it."""

    def __init__(self, kind: str, leading: int = 1):
        super().__init__()
        self.kind, self.leading = kind, leading  # leading: the arguments every term takes before its parameters

    def register(
        self,
        fn=None,
        *,
        size: int = 1,
        needs: tuple[str, ...] = (),
        per: str = "",
        domains: dict[str, Domain] | None = None,
    ):
        """Register `fn` under its own name; its parameters after the first (two for a reset) each need a domain."""

        def add(f):
            sig = {p.name: p for p in list(inspect.signature(f).parameters.values())[self.leading :]}
            given = dict(domains or {})
            if set(given) != set(sig):  # a programming error: caught at import, by every test
                raise TypeError(f"{f.__name__}: domains {sorted(given)} do not match its parameters {sorted(sig)}")
            for name, p in sig.items():
                if given[name].problem(p.default) is not None:
                    raise TypeError(f"{f.__name__}: default {name}={p.default!r} is outside its own domain")
            doc = (f.__doc__ or "").strip().splitlines()[0] if f.__doc__ else ""
            self[f.__name__] = Term(f.__name__, f, sig, doc, size, needs, per, given)
            return f

        return add(fn) if fn is not None else add


REWARD_FEATURES = Registry("reward feature")
OBSERVATION_TERMS = Registry("observation term")
RESET_TERMS = Registry("reset term", leading=2)  # (an EpisodeStart, its random generator, params)
TERMINATION_TERMS = Registry("termination term")
