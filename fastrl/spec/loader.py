"""Load YAML spec files into pydantic models; report every problem as FILE:LINE: path: message."""

from __future__ import annotations

import copy
import typing
from dataclasses import dataclass, field
from typing import Any

import yaml
from pydantic import BaseModel, ValidationError
from yaml.nodes import MappingNode, SequenceNode

from .errors import clean_loc, error_message, number_problems
from .limits import MAX_SPEC_BYTES, open_regular
from .yamlsafe import LimitError, error_line, plain_yaml_problem, text_problems
from .yamlsafe import Loader as _Loader


@dataclass(frozen=True)
class SpecIssue:
    """One problem: where it is and what is wrong."""

    file: str
    line: int | None
    path: str
    message: str

    def __str__(self) -> str:
        file, path, message = _printable(self.file), _printable(self.path), _printable(" ".join(self.message.split()))
        where = file if self.line is None else f"{file}:{self.line}"
        return f"{where}: {path}: {message}" if path else f"{where}: {message}"


def _printable(text: str) -> str:
    """Text with control characters escaped, so an issue is always one line."""
    return text if text.isprintable() else "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class SpecError(Exception):
    """One or more problems in a spec file; str() is the full multi-line report."""

    def __init__(self, errors: list[SpecIssue]):
        self.errors = list(errors)
        super().__init__("\n".join(str(e) for e in self.errors))


@dataclass
class LineMap:
    """1-based source lines of node paths: the key of a mapping entry, the item of a sequence."""

    lines: dict[tuple, int] = field(default_factory=dict)
    root: int | None = None

    def line_for(self, path: tuple) -> int | None:
        """Line of the exact path, else of its nearest recorded ancestor, else of the root."""
        path = tuple(path)
        while path and path not in self.lines:
            path = path[:-1]
        return self.lines[path] if path else self.root


def _fail(file: str, line: int | None, message: str) -> SpecError:
    return SpecError([SpecIssue(file, line, "", message)])


def _yaml_error(file: str, err: yaml.YAMLError, text: str = "") -> SpecError:
    if isinstance(err, yaml.reader.ReaderError):
        line = text[: err.position].count("\n") + 1 if text else None
        return _fail(file, line, f"character U+{err.character:04X} is not allowed in a YAML file (a control character)")
    if isinstance(err, LimitError):
        return SpecError([SpecIssue(file, err.line, err.path, err.message)])
    mark, ctx_mark = getattr(err, "problem_mark", None), getattr(err, "context_mark", None)
    if mark is None:
        return _fail(file, None, "invalid YAML: " + " ".join(str(err).split()))
    return _fail(file, error_line(err), plain_yaml_problem(err, ctx_mark.line + 1 if ctx_mark else None))


def _record_lines(loader: _Loader, node, path: tuple, lines: dict, active: set) -> None:
    if id(node) in active:  # recursive alias
        return
    active.add(id(node))
    if isinstance(node, MappingNode):
        for key_node, value_node in node.value:
            key = loader.construct_object(key_node, deep=True)
            if isinstance(key, typing.Hashable):
                lines[path + (key,)] = key_node.start_mark.line + 1
                _record_lines(loader, value_node, path + (key,), lines, active)
    elif isinstance(node, SequenceNode):
        for i, item in enumerate(node.value):
            lines[path + (i,)] = item.start_mark.line + 1
            _record_lines(loader, item, path + (i,), lines, active)
    active.discard(id(node))


def _yaml_loader(file: str, text: str) -> _Loader:
    try:
        return _Loader(text)
    except yaml.YAMLError as e:  # the reader checks every character first
        raise _yaml_error(file, e, text) from None


def read_yaml(path) -> tuple[Any, LineMap]:
    """Parse a YAML file safely into plain data plus a LineMap; any problem raises SpecError."""
    file = str(path)
    try:
        with open_regular(path, MAX_SPEC_BYTES) as fh:
            raw = fh.read(MAX_SPEC_BYTES + 1)
    except (OSError, ValueError) as e:
        raise _fail(
            file, None, str(e) if isinstance(e, ValueError) else f"cannot read file: {e.strerror or e}"
        ) from None
    if len(raw) > MAX_SPEC_BYTES:
        raise _fail(file, None, f"file is too large: more than {MAX_SPEC_BYTES:,} bytes")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise _fail(file, line, f"file is not valid UTF-8 (byte offset {e.start})") from None
    loader, lines = _yaml_loader(file, text), {}
    try:
        node = loader.get_single_node()
        data = None if node is None else loader.construct_document(node)
        if node is not None:
            _record_lines(loader, node, (), lines, set())
    except yaml.YAMLError as e:
        raise _yaml_error(file, e) from None
    finally:
        loader.dispose()
    if data is None:
        raise _fail(file, None, "file is empty (expected a mapping of fields)")
    if not isinstance(data, dict):
        kind = type(data).__name__
        raise _fail(file, node.start_mark.line + 1, f"top level must be a mapping, got {kind}")
    return data, LineMap(lines, node.start_mark.line + 1)


def yaml_scalar(text: str) -> Any:
    """Parse an override value as a YAML scalar or flow value; ValueError if malformed."""
    try:
        loader = _yaml_loader("--set", text)  # a SafeLoader: only plain data, never objects
    except SpecError as e:
        raise ValueError(f"invalid value {text!r}: {e.errors[0].message}") from None
    try:
        value = loader.get_single_data()
    except yaml.YAMLError as e:
        raise ValueError(f"invalid value {text!r}: {_yaml_error('--set', e).errors[0].message}") from None
    finally:
        loader.dispose()
    if value is None and text.strip() not in ("", "~", "null", "Null", "NULL"):
        return text  # e.g. "#fff" would otherwise vanish as a comment
    return value


def _copy(obj: Any, active: frozenset = frozenset()) -> Any:
    """Deep copy that also un-shares YAML aliases, so an override touches only its own path."""
    if id(obj) in active:
        return obj
    if isinstance(obj, dict):
        return {k: _copy(v, active | {id(obj)}) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_copy(v, active | {id(obj)}) for v in obj]
    return copy.deepcopy(obj)


def _set(data: dict, segs: list[str], value: Any) -> tuple:
    """Set value at segs inside data (creating missing mappings); return the concrete path."""
    node, path = data, ()
    for depth, seg in enumerate(segs):
        here, last = ".".join(segs[:depth]) or "the top level", depth == len(segs) - 1
        if isinstance(node, dict):
            num = seg not in node and seg.lstrip("-").isdigit() and int(seg) in node
            key = int(seg) if num else seg
            if not last and key not in node:
                node[key] = {}
        elif isinstance(node, list):
            if not seg.isdigit() or int(seg) >= len(node):
                raise ValueError(f"{seg!r} is not an index of {here!r} ({len(node)} items)")
            key = int(seg)
        else:
            kind = "null" if node is None else f"a {type(node).__name__}"
            raise ValueError(  # noqa: TRY004 - reported as a bad override, not a bug
                f"cannot descend into {here!r}: it is {kind}, not a mapping or list"
            )
        path += (key,)
        if last:
            node[key] = value
        node = node[key]
    return path


def _apply(data: dict, overrides, source: str) -> tuple[dict, list[tuple[tuple, str]]]:
    data, applied, issues = _copy(data), [], []
    for text in overrides:
        name, eq, raw = text.partition("=")
        try:
            if not eq or not all(segs := name.strip().split(".")):
                raise ValueError("expected dotted.path=value")
            applied.append((_set(data, segs, yaml_scalar(raw)), text))
        except ValueError as e:
            issues.append(SpecIssue(source, None, "", f"bad override {text!r}: {e}"))
    if issues:
        raise SpecError(issues)
    return data, applied


def apply_overrides(data: dict, overrides: list[str], *, source: str = "--set") -> dict:
    """Return a deep copy of data with "dotted.path=value" overrides applied."""
    return _apply(data, overrides, source)[0]


def load_model(path, model_cls: type[BaseModel], overrides: list[str] = (), context: dict | None = None) -> BaseModel:
    """Read a YAML spec, apply overrides, validate into model_cls; SpecError lists every problem."""
    data, lines = read_yaml(path)
    data, applied = _apply(data, overrides, "--set")
    issues = []

    def add(where: tuple, message: str) -> None:
        dotted = ".".join(map(str, where))
        src = [text for p, text in applied if where[: len(p)] == p]  # overridden path?
        if src:
            issue = SpecIssue("--set", None, dotted, f"{message} (from --set {src[-1]!r})")
        else:
            issue = SpecIssue(str(path), lines.line_for(where), dotted, message)
        if issue not in issues:
            issues.append(issue)

    for where, message in number_problems(data) + text_problems(data):
        add(where, message)
    if not issues:
        try:
            return model_cls.model_validate(data, context=context)
        except ValidationError as exc:
            for err in exc.errors():
                where = clean_loc(data, tuple(err["loc"]), keep_last=err["type"] == "missing")
                add(where, error_message(err, data, where, model_cls))
    issues.sort(key=lambda i: (i.line is None, i.line or 0))
    raise SpecError(issues) from None
