"""A bounded YAML SafeLoader: duplicate keys, nesting, list and alias-expansion limits, plain messages."""

from __future__ import annotations

import re
from typing import Any

import yaml
from yaml.nodes import MappingNode, ScalarNode, SequenceNode

from .limits import MAX_YAML_DEPTH, MAX_YAML_ITEMS, MAX_YAML_NODES

# YAML 1.1 reads 1e-3 / 3e5 / 1.5e3 as strings; this extra resolver makes them floats.
_FLOAT_EXP = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$")


class LimitError(yaml.YAMLError):
    """A YAML document beyond a resource limit: where (line, dotted path) and what."""

    def __init__(self, message: str, line: int | None, path: str = ""):
        super().__init__(message)
        self.message, self.line, self.path = message, line, path


class Loader(yaml.SafeLoader):
    """SafeLoader that rejects duplicate keys, reads 1e-3 / 3e5 as floats and refuses oversized documents."""

    def __init__(self, stream):
        super().__init__(stream)
        self._checked: set[int] = set()
        self._depth = 0

    def compose_node(self, parent, index):
        """Compose one node, refusing nesting deeper than MAX_YAML_DEPTH before it can exhaust the stack."""
        if self._depth >= MAX_YAML_DEPTH:
            line = self.peek_event().start_mark.line + 1
            raise LimitError(f"nested more than {MAX_YAML_DEPTH} levels deep (lists and mappings)", line)
        self._depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def get_single_node(self):
        """The document's node graph, checked for size (aliases expanded) before anything is built from it."""
        node = super().get_single_node()
        if node is not None:
            check_graph(node)
        return node

    def flatten_mapping(self, node):
        if id(node) not in self._checked:  # check before merge keys (<<) are folded in
            self._checked.add(id(node))
            seen: dict[Any, int] = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    dup = key in seen
                except TypeError:
                    continue  # unhashable key: the base constructor reports it
                if dup:
                    msg = f"duplicate key {key!r} (first at line {seen[key]})"
                    raise yaml.constructor.ConstructorError(None, None, msg, key_node.start_mark)
                seen[key] = key_node.start_mark.line + 1
        super().flatten_mapping(node)


Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_EXP, list("-+0123456789."))


def check_graph(root) -> None:
    """Refuse a node graph that is cyclic, too deep or too large once every alias is expanded (LimitError)."""
    sizes: dict[int, tuple[int, int]] = {}  # id -> (values, height) of the expanded subtree
    active: set[int] = set()

    def fail(node, path: tuple, message: str):
        raise LimitError(message, node.start_mark.line + 1, ".".join(map(str, path)))

    def visit(node, depth: int, path: tuple) -> tuple[int, int]:
        key = id(node)
        if key in active:
            fail(node, path, "an alias (*name) refers to a list or mapping that contains it")
        if key in sizes:
            size, height = sizes[key]
            if depth + height > MAX_YAML_DEPTH:
                fail(node, path, f"nested more than {MAX_YAML_DEPTH} levels deep once aliases (*name) are followed")
            return sizes[key]
        if depth > MAX_YAML_DEPTH:
            fail(node, path, f"nested more than {MAX_YAML_DEPTH} levels deep once aliases (*name) are followed")
        if isinstance(node, SequenceNode):
            children = [(item, path + (i,)) for i, item in enumerate(node.value)]
        elif isinstance(node, MappingNode):
            children = []
            for k, v in node.value:
                label = k.value if isinstance(k, ScalarNode) else "?"
                children += [(k, path + (label,)), (v, path + (label,))]
        else:
            children = []
        if len(node.value) > MAX_YAML_ITEMS and not isinstance(node, ScalarNode):
            fail(node, path, f"{len(node.value):,} entries in one list or mapping, at most {MAX_YAML_ITEMS:,} allowed")
        active.add(key)
        size, height = 1, 0
        for child, where in children:
            s, h = visit(child, depth + 1, where)
            size, height = size + s, max(height, h + 1)
            if size > MAX_YAML_NODES:
                fail(
                    node,
                    path,
                    f"more than {MAX_YAML_NODES:,} values once aliases (*name) are expanded: "
                    "a spec needs far fewer (is an alias repeated to inflate the file?)",
                )
        active.discard(key)
        sizes[key] = (size, height)
        return size, height

    visit(root, 0, ())


# PyYAML's wording -> a plain sentence; {c}: the line where the enclosing construct starts, {1}: a captured group
_PLAIN = [
    (
        r"expected <block end>, but found",
        "this line's indentation does not match the block that starts at line {c}: the keys of one mapping "
        "and the items of one list must start in the same column",
    ),
    (
        r"mapping values are not allowed here",
        "unexpected ':' here: check this line's indentation against the lines above, and put a value "
        "that contains ': ' in quotes",
    ),
    (r"found character '\\t' that cannot start any token", "a tab character: indent YAML with spaces only"),
    (r"found character '(.)' that cannot start any token", "'{1}' cannot start a value: put the value in quotes"),
    (r"found unexpected end of stream", "a quoted text that starts at line {c} is never closed"),
    (
        r"could not find expected ':'",
        "this line is neither 'key: value' nor a list item '- value': a ':' followed by a space is missing",
    ),
    (
        r"expected ',' or '\]'",
        "the list '[...]' opened at line {c} is not closed with ']', or its items lack a ',' between them",
    ),
    (
        r"expected ',' or '\}'",
        "the mapping '{{...}}' opened at line {c} is not closed with '}}', or its entries lack a ',' between them",
    ),
    (r"found undefined alias '(.*)'", "'*{1}' refers to no anchor '&{1}' defined above it"),
    (r"second occurrence", "this anchor is defined twice (first at line {c})"),
    (r"but found another document", "a second YAML document ('---' or '...'): a spec file holds one"),
    (r"expected '<document start>'", "text after the end of the document ('...')"),
    (
        r"could not determine a constructor for the tag '(.*)'",
        "the tag '{1}' is not allowed: a spec holds plain numbers, text, lists and mappings only",
    ),
    (r"found unhashable key", "a list or mapping used as a key: keys must be plain names"),
    (r"found unknown escape character '(.*)'", "unknown escape '\\{1}' in a double-quoted text: use single quotes"),
    (r"expected the node content, but found '(.*)'", "expected a value here, found '{1}'"),
]


def error_line(err: yaml.YAMLError) -> int | None:
    """The 1-based line to show for a PyYAML error: where the broken construct starts when PyYAML only noticed
    later (an unclosed quote at the end of the file, a key without ':' on the next line)."""
    mark, ctx_mark = getattr(err, "problem_mark", None), getattr(err, "context_mark", None)
    if mark is None:
        return None
    problem = str(getattr(err, "problem", ""))
    if ctx_mark is not None and ("end of stream" in problem or "could not find expected ':'" in problem):
        return ctx_mark.line + 1
    return mark.line + 1


def plain_yaml_problem(err: yaml.YAMLError, context_line: int | None) -> str:
    """One plain sentence for a PyYAML error (what is wrong and how to fix it); PyYAML's own words otherwise."""
    problem = " ".join(str(getattr(err, "problem", None) or "").split())
    for pattern, sentence in _PLAIN:
        m = re.search(pattern, problem)
        if m and ("{c}" not in sentence or context_line is not None):
            return sentence.format(*([m.group(0), *m.groups()]), c=context_line)
    context = " ".join(str(getattr(err, "context", None) or "").split())
    if problem.startswith("duplicate key"):
        return problem
    where = f" ({context}" + (f" at line {context_line})" if context_line else ")") if context else ""
    return f"invalid YAML: {problem or 'syntax error'}{where}"


_SURROGATE = re.compile("[\ud800-\udfff]")


def text_problems(data: Any) -> list[tuple[tuple, str]]:
    """(path, problem) for every key or text value holding a lone UTF-16 surrogate ("\\ud800"): not a character."""
    problems, stack = [], [(data, ())]
    while stack:
        node, path = stack.pop()
        if isinstance(node, dict):
            for k, v in node.items():
                if isinstance(k, str) and _SURROGATE.search(k):
                    problems.append((path + (k,), _surrogate_message(k, "key")))
                stack.append((v, path + (k,)))
        elif isinstance(node, list):
            stack += [(v, path + (i,)) for i, v in enumerate(node)]
        elif isinstance(node, str) and _SURROGATE.search(node):
            problems.append((path, _surrogate_message(node, "text")))
    return problems


def _surrogate_message(text: str, what: str) -> str:
    """The one-line explanation for a text holding a lone surrogate."""
    code = ord(_SURROGATE.search(text).group())
    return (
        f"this {what} holds \\u{code:04x}, half of a UTF-16 surrogate pair, which is not a character: "
        "write the character itself, or escape it whole as \\UXXXXXXXX"
    )
