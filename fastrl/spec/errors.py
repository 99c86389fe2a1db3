"""Pydantic's validation errors said in a spec's words: where in the data, what is wrong, the likely field name."""

from __future__ import annotations

import difflib
import math
import re
import types
import typing
from collections.abc import Mapping, Sequence
from collections.abc import Set as AbstractSet
from typing import Any, Literal

from pydantic import BaseModel

from .limits import MAX_INT


def _flatten(tps) -> list:
    """The concrete types inside Annotated and Union types."""
    out = []
    for tp in tps:
        origin = typing.get_origin(tp)
        if origin is typing.Annotated:
            out += _flatten(typing.get_args(tp)[:1])
        elif origin in (typing.Union, types.UnionType):
            out += _flatten(typing.get_args(tp))
        else:
            out.append(tp)
    return out


def _fields(tp) -> dict[str, Any]:
    """A model class's fields by name (alias first); {} for anything else."""
    if not (isinstance(tp, type) and issubclass(tp, BaseModel)):
        return {}
    return {f.alias or n: f.annotation for n, f in tp.model_fields.items()}


def _models_at(model_cls: type[BaseModel], loc: tuple) -> list[type[BaseModel]]:
    """Model classes a raw pydantic loc (union tags included) may point at."""
    tps = [model_cls]
    for seg in loc:
        nxt, tagged = [], []
        for tp in _flatten(tps):
            origin, args, fields = typing.get_origin(tp), typing.get_args(tp), _fields(tp)
            lits = [typing.get_args(a) for a in fields.values() if typing.get_origin(a) is Literal]
            if seg in fields:
                nxt.append(fields[seg])
            elif fields and (seg == tp.__name__ or any(seg in lit for lit in lits)):
                tagged.append(tp)  # seg is this union member's tag
            elif not isinstance(origin, type):
                continue
            elif issubclass(origin, Mapping) and args:
                nxt.append(args[-1])
            elif issubclass(origin, (Sequence, AbstractSet)) and isinstance(seg, int):
                nxt += [a for a in args if a is not Ellipsis]
        tps = nxt or tagged or tps  # a segment nothing consumes is a marker: skip it
    return [tp for tp in _flatten(tps) if _fields(tp)]


def clean_loc(data: Any, loc: tuple, keep_last: bool) -> tuple:
    """Keep only loc segments that exist in data (drops union tags, function-after[...] markers)."""
    path, node = (), data
    for i, seg in enumerate(loc):
        in_list = isinstance(node, list) and isinstance(seg, int) and 0 <= seg < len(node)
        if in_list or (isinstance(node, dict) and seg in node):
            node = node[seg]
        elif not (keep_last and i == len(loc) - 1):
            continue
        path += (seg,)
    return path


def error_message(err: dict, data: Any, path: tuple, model_cls: type[BaseModel]) -> str:
    """One pydantic error as a sentence: missing and unknown fields by name (with the closest known one)."""
    kind, loc = err["type"], err["loc"]
    if kind == "missing" and loc:
        return f"missing required field {loc[-1]!r}"
    if kind == "extra_forbidden" and loc:
        known = {n for m in _models_at(model_cls, loc[:-1]) for n in _fields(m)}
        close = difflib.get_close_matches(str(loc[-1]), sorted(known), n=1)
        return f"unknown field {loc[-1]!r}" + (f" (did you mean {close[0]!r}?)" if close else "")
    if kind == "finite_number":
        return f"expected a finite number, got {err['input']!r}"
    return re.sub(r"^(Value error|Assertion failed), ", "", err["msg"])


def number_problems(data: Any) -> list[tuple[tuple, str]]:
    """(path, problem) for every non-finite number (.inf, .nan) and every integer beyond 2^63 - 1 in the data."""
    problems, stack = [], [(data, ())]
    while stack:
        node, path = stack.pop()
        if isinstance(node, dict):
            stack += [(v, path + (k,)) for k, v in node.items()]
        elif isinstance(node, list):
            stack += [(v, path + (i,)) for i, v in enumerate(node)]
        elif isinstance(node, float) and not math.isfinite(node):
            shown = ".nan" if math.isnan(node) else ("-.inf" if node < 0 else ".inf")
            problems.append((path, f"expected a finite number, got {shown}"))
        elif isinstance(node, int) and not isinstance(node, bool) and abs(node) > MAX_INT:
            problems.append((path, f"integer {node:.3g} is too large (at most 2^63 - 1)"))
    return sorted(problems, key=lambda p: tuple(map(str, p[0])))
