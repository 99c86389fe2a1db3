"""Defaults that depend on the algorithms (train.algo, irl.algorithm): resolved once, when a spec is validated."""

from __future__ import annotations

from typing import Any


def algorithm_defaults(spec) -> dict[tuple[str, ...], Any]:
    """The defaults of a TaskSpec that depend on its algorithms, by field path.

    The discriminator's only when a discriminator is trained: a spec without one (a study's) is run later as
    GAIL and as AIRL, and must resolve them then."""
    kind = spec.train.kind
    defaults: dict[tuple[str, ...], Any] = {("train", "normalize", "reward"): kind.normalize_reward}
    if spec.irl.algorithm in ("gail", "airl"):
        gail = spec.irl.algorithm == "gail"
        d = ("irl", "discriminator")
        defaults[(*d, "ignore")] = ["elapsed"] if gail and "elapsed" in spec.observation.terms() else []
        defaults[(*d, "policy_term")] = kind.policy_term
        defaults[(*d, "scale_reward")] = not gail
    return defaults


def _get(model, path: tuple[str, ...]) -> Any:
    """A nested field's value."""
    for name in path:
        model = getattr(model, name)
    return model


def _replace(model, path: tuple[str, ...], value):
    """A copy of a frozen model with one nested field replaced."""
    if len(path) == 1:
        return model.model_copy(update={path[0]: value})
    return model.model_copy(update={path[0]: _replace(getattr(model, path[0]), path[1:], value)})


def resolve_defaults(spec):
    """A copy of a TaskSpec with each null algorithm-dependent field set to its default (the spec itself if none)."""
    for path, value in algorithm_defaults(spec).items():
        if _get(spec, path) is None:
            spec = _replace(spec, path, value)
    return spec


def drop_unused_extensions(data: dict) -> dict:
    """Leave out instruments, loose bodies and cup where a spec has none: it keeps the hashes it had before them."""
    if not data.get("instruments", True):
        del data["instruments"]
    task = data.get("task", {})
    for key, empty in (("bodies", []), ("cup", None)):
        if key in task and task[key] == empty:
            del task[key]
    return data


def canonical_dump(spec) -> dict:
    """The spec as JSON data with every algorithm-dependent field that holds its default written as null, so a spec
    hashes the same whether it was resolved or not."""
    data = drop_unused_extensions(spec.model_dump(mode="json"))
    for path, value in algorithm_defaults(spec).items():
        node = data
        for name in path[:-1]:
            node = node[name]
        if node[path[-1]] == value:
            node[path[-1]] = None
    return data
