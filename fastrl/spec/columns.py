"""Which observation columns each learned network sees: the column layout a spec's observation terms make."""

from __future__ import annotations

from ..terms import OBSERVATION_TERMS
from .irl import ppo_generator


def column_terms(spec) -> list[str]:
    """The observation term of each column of one frame."""
    coords = [i.coordinates for i in spec.instruments]
    return [n for n in spec.observation.terms() for _ in range(OBSERVATION_TERMS[n].width(coords))]


def columns_without(spec, terms: list[str]) -> list[int] | None:
    """Observation columns of every term but these (every frame of a stack); None: all of them."""
    names = column_terms(spec)
    keep = [i for i, n in enumerate(names * spec.observation.stack) if n not in terms]
    return None if len(keep) == len(names) * spec.observation.stack else keep


def discriminator_inputs(spec) -> list[int] | None:
    """Observation columns the discriminator sees (every frame of a stack); None: all of them."""
    return columns_without(spec, spec.irl.discriminator.ignore or [])


def reward_inputs(spec) -> list[int] | None:
    """Observation columns shaped AIRL's reward r_psi sees: the discriminator's less `reward_ignore`."""
    d = spec.irl.discriminator
    return columns_without(spec, [*(d.ignore or []), *d.reward_ignore])


def value_inputs(spec) -> list[int] | None:
    """Observation columns the inverse-RL generator's critic (the learned value) sees; None: all of them."""
    generator = ppo_generator(spec.train, spec.irl)
    return columns_without(spec, generator.value_ignore) if generator is not None else None
