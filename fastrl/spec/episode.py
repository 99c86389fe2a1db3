"""The spec's episode section: control rate, substeps, time limit, and the declared reset and termination terms."""

from __future__ import annotations

from typing import Any

from pydantic import Field, model_validator

from ..terms import RESET_TERMS, TERMINATION_TERMS
from ..terms.registry import Registry
from .base import Pos, Strict, _fail, _raise
from .limits import MAX_EPISODE_STEPS, MAX_SECONDS

DEFAULT_TERMINATIONS = {"subtasks_done": {}}  # every subtask done: the task's end


class Episode(Strict):
    """Control rate, physics substeps, time limit (a truncation), what each start randomises and what ends it."""

    control_hz: float = Field(20.0, ge=1, le=1000)
    substeps: int = Field(25, ge=1, le=200)
    time_limit: Pos = 60.0
    resets: dict[str, dict[str, Any]] = Field(
        {}, description="reset terms by name with their parameters (fastrl.terms.episode), applied at every start"
    )
    terminations: dict[str, dict[str, Any]] = Field(
        DEFAULT_TERMINATIONS,
        min_length=1,
        description="termination terms by name with their parameters: the episode ends when any holds",
    )

    @model_validator(mode="after")
    def _steps(self):
        steps = round(self.time_limit * self.control_hz)
        if steps < 1:
            step = 1 / self.control_hz
            _fail("time_limit", f"time limit {self.time_limit:g} s is shorter than one control step ({step:g} s)")
        if self.time_limit > MAX_SECONDS:
            _fail("time_limit", f"time limit {self.time_limit:g} s is more than a day ({MAX_SECONDS:,} s)")
        if steps > MAX_EPISODE_STEPS:
            _fail(
                "time_limit",
                f"time limit {self.time_limit:g} s is {steps:,} control steps, at most {MAX_EPISODE_STEPS:,} allowed",
            )
        return self

    @model_validator(mode="after")
    def _known_terms(self):
        _raise(
            term_errors("resets", self.resets, RESET_TERMS)
            + term_errors("terminations", self.terminations, TERMINATION_TERMS)
        )
        return self


def term_errors(field: str, declared: dict[str, dict[str, Any]], registry: Registry) -> list[tuple[tuple, str, Any]]:
    """(location, problem, value) for every declared term the registry lacks and every parameter it refuses."""
    errors = []
    for name, params in declared.items():
        if name not in registry:
            errors.append(((field, name), f"unknown {registry.kind} '{name}' (known: {', '.join(registry)})", name))
            continue
        errors += [((field, name, key), problem, params[key]) for key, problem in registry[name].check_params(params)]
    return errors


def episode_term_errors(spec) -> list[tuple[tuple, str, Any]]:
    """The declared terms a spec's task cannot take: jitter of a tour's fixed landmarks, noise of no instrument."""
    resets, errors = spec.episode.resets, []
    if "avatar_jitter" in resets and spec.task.kind == "liver_tour":
        problem = "liver_tour has landmarks fixed to the anatomy: no avatar_jitter"
        errors.append((("episode", "resets", "avatar_jitter"), problem, resets["avatar_jitter"]))
    if "instrument_noise" in resets and not spec.instruments:
        problem = "instrument_noise needs instruments: this spec has none"
        errors.append((("episode", "resets", "instrument_noise"), problem, resets["instrument_noise"]))
    return errors
