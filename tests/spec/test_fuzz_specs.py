"""Fuzzing task specs: mutated text, mutated values and hostile overrides either load (and compile) or raise
SpecError with one-line FILE:LINE issues; never another exception, never a hang."""

from __future__ import annotations

import math
from datetime import timedelta
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fastrl.cli import load
from fastrl.env.fast_env import FastEnv
from fastrl.spec import SpecError
from fastrl.terms import REWARD_FEATURES

SPECS = Path(__file__).resolve().parents[2] / "specs"
TEXTS = {p.stem: p.read_text(encoding="utf-8") for p in sorted(SPECS.glob("*.yaml"))}
FUZZ = settings(
    max_examples=100,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
pytestmark = pytest.mark.timeout(120)

# Fragments that have broken YAML loaders: structure, anchors and aliases, tags, control characters, extremes.
TOKENS = [
    "[", "]", "{", "}", ":", ": ", "- ", ",", "&a ", "*a", "<<: *a", "!!python/object:os.system ", "!!binary ",
    "\t", "\x00", "\x07", "\ufeff", "\u2028", '"', "'", "#", "\n", "  ", "---\n", "...\n", "? ", "|", ">",
    ".inf", "-.inf", ".nan", "1e999", "-1e-999", "1e300", "0", "-1", "99999999999999999999999", "0x1f", "0o17",
    "1_000", "null", "~", "true", "no", "2001-12-14", "[" * 50, "]" * 50, "é", "\U0001f600",
]  # fmt: skip

# Values a field may be set to: wrong types, extremes, non-finite numbers, deep and long structures.
VALUES = st.one_of(
    st.sampled_from([None, True, False, 0, -1, 1, 2**63, -(2**63) - 1, 10**30, float("inf"), float("-inf")]),
    st.sampled_from([float("nan"), 1e-300, -1e300, 1e300, "", "x" * 1000, "inf", "nan", "-Infinity", "1e999"]),
    st.sampled_from([[], {}, [[]], [0.0] * 2000, [[0.1, 0.1]] * 300, {"a": {"b": {"c": 1}}}]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.text(max_size=20),
    st.recursive(st.integers() | st.text(max_size=3), lambda c: st.lists(c, max_size=3), max_leaves=40),
)


def check(path: Path, overrides=()) -> None:
    """The property: load and compile, or a SpecError whose issues are single lines naming the file or --set."""
    try:
        load(path, list(overrides))
    except SpecError as e:
        assert e.errors
        for issue in e.errors:
            text = str(issue)
            assert "\n" not in text and (text.startswith(f"{path}") or text.startswith("--set")), text


@FUZZ
@given(
    name=st.sampled_from(sorted(TEXTS)),
    edits=st.lists(
        st.tuples(
            st.sampled_from(["insert", "delete", "duplicate", "indent", "number"]),
            st.floats(0, 1),
            st.sampled_from(TOKENS) | st.text(max_size=8),
        ),
        min_size=1,
        max_size=4,
    ),
)
def test_mutated_spec_text(tmp_path_factory, name, edits):
    """Insert tokens, delete spans, duplicate or re-indent lines, replace numbers with extremes."""
    text = TEXTS[name]
    for kind, where, token in edits:
        i = int(where * len(text))
        lines = text.split("\n")
        n = min(int(where * len(lines)), len(lines) - 1)
        if kind == "insert":
            text = text[:i] + token + text[i:]
        elif kind == "delete":
            text = text[:i] + text[i + 1 + len(token) :]
        elif kind == "duplicate":
            text = "\n".join(lines[: n + 1] + lines[n:])
        elif kind == "indent":
            text = "\n".join(lines[:n] + [" " * (len(token) % 5) + lines[n].lstrip()] + lines[n + 1 :])
        else:
            digits = [k for k, c in enumerate(text) if c.isdigit()]
            k = digits[int(where * (len(digits) - 1))]
            text = text[:k] + token + text[k + 1 :]
    path = tmp_path_factory.getbasetemp() / f"mutated_{name}.yaml"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    check(path)


def paths_of(data, prefix=()) -> list[tuple]:
    """Every key path in nested mappings and lists."""
    out = [prefix] if prefix else []
    if isinstance(data, dict):
        for k, v in data.items():
            out += paths_of(v, prefix + (k,))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            out += paths_of(v, prefix + (i,))
    return out


DATA = {name: yaml.safe_load(text) for name, text in TEXTS.items()}
PATHS = {name: paths_of(data) for name, data in DATA.items()}


@FUZZ
@given(name=st.sampled_from(sorted(TEXTS)), picks=st.lists(st.tuples(st.floats(0, 1), VALUES), min_size=1, max_size=3))
def test_mutated_spec_values(tmp_path_factory, name, picks):
    """Set random fields of a shipped spec to wrong types, extremes, non-finite numbers or big structures."""
    import copy

    data = copy.deepcopy(DATA[name])
    for where, value in picks:
        path = PATHS[name][int(where * (len(PATHS[name]) - 1))]
        node = data
        for seg in path[:-1]:
            node = node[seg] if isinstance(node, dict | list) and _has(node, seg) else None
        if isinstance(node, dict | list) and _has(node, path[-1]):
            node[path[-1]] = value
    file = tmp_path_factory.getbasetemp() / f"values_{name}.yaml"
    file.write_text(yaml.safe_dump(data, allow_unicode=True), encoding="utf-8")
    check(file)


def _has(node, seg) -> bool:
    return seg in node if isinstance(node, dict) else isinstance(seg, int) and seg < len(node)


@FUZZ
@given(
    key=st.sampled_from([p for p in PATHS["tracelines"] if all(isinstance(s, str) for s in p)]).map(
        lambda p: ".".join(p)
    )
    | st.text(min_size=1, max_size=12),
    value=st.sampled_from(TOKENS) | st.text(max_size=30),
)
def test_hostile_overrides(key, value):
    """--set KEY=VALUE with any key and any text: loads or names the override."""
    check(SPECS / "tracelines.yaml", [f"{key}={value}"])


# Term parameters: the values that have broken features (zero, negative, subnormal, huge, non-finite, wrong types).
PARAM_VALUES = st.one_of(
    st.sampled_from([0, 0.0, -0.0, -0.02, -1, 5e-324, 1e-300, 1e-7, 1e-6, 1e-3, 0.02, 1, 179.0, 180.0, 1e300]),
    st.sampled_from([float("nan"), float("inf"), float("-inf"), True, None, "0.02", [], 2**63]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**64), max_value=2**64),
)
STEP = settings(FUZZ, max_examples=40, deadline=timedelta(seconds=60))


@st.composite
def reward_features(draw) -> dict:
    """One to four registered features, parametrised ones first, each with a weight and some mutated parameters."""
    names = sorted(REWARD_FEATURES, key=lambda n: (not REWARD_FEATURES[n].params, n))
    chosen = draw(st.lists(st.sampled_from(names[:8]) | st.sampled_from(names), min_size=1, max_size=4, unique=True))
    out = {}
    for name in chosen:
        keys = draw(st.lists(st.sampled_from([*REWARD_FEATURES[name].params, "margn"]), max_size=3, unique=True))
        params = {k: draw(PARAM_VALUES) for k in keys if k != "margn" or draw(st.integers(0, 9)) == 0}
        out[name] = {"weight": draw(st.sampled_from([-1.0, 1.0]) | st.floats(-1, 1)), "params": params}
    return out


@STEP
@given(name=st.sampled_from(sorted(TEXTS)), features=reward_features(), seed=st.integers(0, 2**16))
def test_accepted_term_parameters_step_1000_times(tmp_path_factory, name, features, seed):
    """Reward features with mutated parameters: refused by `fastrl check` with FILE:LINE, or 1,000 finite steps."""
    import copy

    data = copy.deepcopy(DATA[name])
    data["reward"]["features"].update(features)
    file = tmp_path_factory.getbasetemp() / f"params_{name}.yaml"
    file.write_text(yaml.safe_dump(data, allow_unicode=True), encoding="utf-8")
    try:
        task = load(file)
    except SpecError as e:
        assert all(str(i).startswith(f"{file}:") and "\n" not in str(i) for i in e.errors), e
        return
    env = FastEnv(task.spec)
    env.reset(seed=seed)
    env.action_space.seed(seed)
    for _ in range(1000):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert math.isfinite(reward) and np.isfinite(obs).all(), (features, reward)
        if terminated or truncated:
            env.reset()
    env.close()
