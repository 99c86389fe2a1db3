"""Tests for the generic YAML -> pydantic spec loader."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Annotated, Literal

import pytest
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    ValidationInfo,
    field_validator,
    model_validator,
)

from fastrl.spec.loader import (
    LineMap,
    SpecError,
    SpecIssue,
    apply_overrides,
    load_model,
    read_yaml,
    yaml_scalar,
)

CFG = ConfigDict(frozen=True, extra="forbid")


class Train(BaseModel):
    model_config = CFG
    timesteps: int
    learning_rate: float = 3e-4
    batch_size: int = 64

    @field_validator("timesteps")
    @classmethod
    def _positive(cls, v: int) -> int:
        if v <= 0:
            raise ValueError("timesteps must be positive")
        return v


class Pos(BaseModel):
    model_config = CFG
    x: float
    y: float


class Avatar(BaseModel):
    model_config = CFG
    name: str
    pos: Pos
    dwell: float = 0.0


class Ring(BaseModel):
    model_config = CFG
    kind: Literal["ring"]
    radius: float


class Peg(BaseModel):
    model_config = CFG
    kind: Literal["peg"]
    length: float


class Window(BaseModel):
    model_config = CFG
    lo: float
    hi: float

    @model_validator(mode="after")
    def _ordered(self) -> Window:
        if self.lo >= self.hi:
            raise ValueError("lo must be below hi")
        return self


class Task(BaseModel):
    model_config = CFG
    name: str
    train: Train
    avatars: list[Avatar] = []
    target: Annotated[Ring | Peg, Field(discriminator="kind")]
    window: Window | None = None
    weights: dict[str, float] = {}
    tags: list[str] = []

    @field_validator("name")
    @classmethod
    def _ctx(cls, v: str, info: ValidationInfo) -> str:
        if info.context and v in info.context.get("banned", ()):
            raise ValueError(f"name {v!r} is banned")
        return v


GOOD = """\
name: demo
train:
  timesteps: 1000
  learning_rate: 1e-3
avatars:
  - name: a
    pos: {x: 0, y: 1}
  - name: b
    pos:
      x: 2
      y: 3
    dwell: 0.5
target:
  kind: ring
  radius: 0.02
window: {lo: 0, hi: 1}
"""


def write(tmp_path: Path, text: str, name: str = "spec.yaml") -> Path:
    p = tmp_path / name
    p.write_text(textwrap.dedent(text), encoding="utf-8")
    return p


def issues(exc: pytest.ExceptionInfo[SpecError]) -> list[tuple[int | None, str, str]]:
    return [(e.line, e.path, e.message) for e in exc.value.errors]


# --- happy path --------------------------------------------------------------


def test_loads_valid_file(tmp_path):
    task = load_model(write(tmp_path, GOOD), Task)
    assert task.train.learning_rate == 0.001
    assert task.avatars[1].pos == Pos(x=2, y=3)
    assert isinstance(task.target, Ring)
    assert task.window == Window(lo=0, hi=1)


def test_accepts_str_path(tmp_path):
    p = write(tmp_path, GOOD)
    assert load_model(str(p), Task).name == "demo"


def test_read_yaml_lines(tmp_path):
    data, lines = read_yaml(write(tmp_path, GOOD))
    assert data["train"]["learning_rate"] == 0.001
    assert lines.line_for(("train",)) == 2
    assert lines.line_for(("train", "learning_rate")) == 4
    assert lines.line_for(("avatars", 0)) == 6
    assert lines.line_for(("avatars", 1)) == 8
    assert lines.line_for(("avatars", 1, "pos", "y")) == 11
    assert lines.line_for(("avatars", 1, "pos", "nope", "deeper")) == 9  # nearest ancestor
    assert lines.line_for(("missing",)) == 1  # root
    assert lines.line_for(()) == 1


def test_line_map_standalone():
    lm = LineMap({("a",): 3, ("a", "b"): 4}, root=1)
    assert lm.line_for(("a", "b", "c")) == 4
    assert lm.line_for(("z",)) == 1
    assert LineMap().line_for(("z",)) is None


def test_float_exponents_in_files(tmp_path):
    data, _ = read_yaml(write(tmp_path, "a: 1e-3\nb: 3e5\nc: -2.5e+2\nd: 1.5E3\ne: 1_000\nf: '1e-3'\ng: 1e\nh: 2.0\n"))
    assert data == {
        "a": 0.001,
        "b": 300000.0,
        "c": -250.0,
        "d": 1500.0,
        "e": 1000,
        "f": "1e-3",
        "g": "1e",
        "h": 2.0,
    }
    assert isinstance(data["b"], float)


def test_plain_safeloader_not_mutated(tmp_path):
    import yaml

    assert yaml.safe_load("a: 1e-3") == {"a": "1e-3"}


def test_merge_keys_are_not_duplicates(tmp_path):
    text = """\
    base: &b {x: 1, y: 2}
    other:
      <<: *b
      y: 5
    """
    data, lines = read_yaml(write(tmp_path, text))
    assert data["other"] == {"x": 1, "y": 5}
    assert lines.line_for(("other", "y")) == 4


def test_unsafe_tags_rejected(tmp_path):
    p = write(tmp_path, "a: !!python/object/apply:os.system ['echo hi']\n")
    with pytest.raises(SpecError) as exc:
        read_yaml(p)
    assert exc.value.errors[0].line == 1
    assert "python/object/apply" in str(exc.value)


# --- validation errors with lines --------------------------------------------


def test_unknown_key_in_nested_mapping_with_suggestion(tmp_path):
    text = GOOD.replace("  timesteps: 1000\n", "  timesteps: 1000\n  batch_siz: 8\n")
    p = write(tmp_path, text)
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(4, "train.batch_siz", "unknown field 'batch_siz' (did you mean 'batch_size'?)")]
    assert str(exc.value) == f"{p}:4: train.batch_siz: unknown field 'batch_siz' (did you mean 'batch_size'?)"


def test_did_you_mean_names_the_close_field_even_when_present(tmp_path):
    p = write(
        tmp_path,
        "name: n\ntrain: {timesteps: 5, batch_size: 2, batch_sizes: 3}\ntarget: {kind: ring, radius: 1}\n",
    )
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(2, "train.batch_sizes", "unknown field 'batch_sizes' (did you mean 'batch_size'?)")]


def test_unknown_key_without_close_match(tmp_path):
    p = write(tmp_path, GOOD + "zzz: 1\n")
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(17, "zzz", "unknown field 'zzz'")]


def test_wrong_type_inside_list_item(tmp_path):
    p = write(tmp_path, GOOD.replace("      y: 3", "      y: three"))
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    [(line, path, msg)] = issues(exc)
    assert (line, path) == (11, "avatars.1.pos.y")
    assert "valid number" in msg


def test_missing_field_points_at_parent(tmp_path):
    p = write(
        tmp_path,
        GOOD.replace("  - name: a\n    pos: {x: 0, y: 1}\n", "  - name: a\n    pos: {x: 0}\n"),
    )
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(7, "avatars.0.pos.y", "missing required field 'y'")]


def test_missing_top_level_field(tmp_path):
    p = write(tmp_path, "# comment\nname: x\ntrain: {timesteps: 1}\n")
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(2, "target", "missing required field 'target'")]


def test_model_validator_points_at_mapping(tmp_path):
    p = write(tmp_path, GOOD.replace("window: {lo: 0, hi: 1}", "window: {lo: 2, hi: 1}"))
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(16, "window", "lo must be below hi")]


def test_field_validator_error(tmp_path):
    p = write(tmp_path, GOOD.replace("timesteps: 1000", "timesteps: -5"))
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(3, "train.timesteps", "timesteps must be positive")]


def test_context_is_passed(tmp_path):
    p = write(tmp_path, GOOD)
    with pytest.raises(SpecError) as exc:
        load_model(p, Task, context={"banned": ["demo"]})
    assert issues(exc) == [(1, "name", "name 'demo' is banned")]


def test_discriminated_union_tag_dropped_from_path(tmp_path):
    p = write(tmp_path, GOOD.replace("  kind: ring\n  radius: 0.02\n", "  kind: peg\n  lenght: 1\n"))
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [
        (13, "target.length", "missing required field 'length'"),
        (15, "target.lenght", "unknown field 'lenght' (did you mean 'length'?)"),
    ]


def test_discriminated_union_bad_tag(tmp_path):
    p = write(tmp_path, GOOD.replace("kind: ring", "kind: cube"))
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    [(line, path, msg)] = issues(exc)
    assert (line, path) == (13, "target")
    assert "'cube'" in msg and "'ring', 'peg'" in msg


def test_dict_values_and_list_of_scalars(tmp_path):
    p = write(tmp_path, GOOD + "weights:\n  time: fast\ntags: [a, 3]\n")
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert [(line, path) for line, path, _ in issues(exc)] == [(18, "weights.time"), (19, "tags.1")]


def test_several_errors_all_reported_sorted_by_line(tmp_path):
    text = """\
    name: demo
    train:
      timesteps: many
      extra_knob: 1
    avatars:
      - name: a
        pos: {x: 0, y: 1}
      - pos: {x: 0, y: nope}
    target: {kind: ring}
    window: {lo: 0, hi: 1, mid: 0.5}
    """
    with pytest.raises(SpecError) as exc:
        load_model(write(tmp_path, text), Task)
    got = [(line, path) for line, path, _ in issues(exc)]
    assert got == [
        (3, "train.timesteps"),
        (4, "train.extra_knob"),
        (8, "avatars.1.name"),
        (8, "avatars.1.pos.y"),
        (9, "target.radius"),
        (10, "window.mid"),
    ]
    assert len(str(exc.value).splitlines()) == 6
    assert "Traceback" not in str(exc.value)


# --- YAML-level errors ---------------------------------------------------------


def test_duplicate_key(tmp_path):
    p = write(tmp_path, "name: a\ntrain:\n  timesteps: 1\n  timesteps: 2\n")
    with pytest.raises(SpecError) as exc:
        read_yaml(p)
    assert issues(exc) == [(4, "", "duplicate key 'timesteps' (first at line 3)")]
    assert str(exc.value) == f"{p}:4: duplicate key 'timesteps' (first at line 3)"


def test_duplicate_key_flow_and_top_level(tmp_path):
    with pytest.raises(SpecError) as exc:
        read_yaml(write(tmp_path, "a: {x: 1, x: 2}\n"))
    assert issues(exc) == [(1, "", "duplicate key 'x' (first at line 1)")]
    with pytest.raises(SpecError) as exc:
        read_yaml(write(tmp_path, "a: 1\nb: 2\n\na: 3\n"))
    assert issues(exc) == [(4, "", "duplicate key 'a' (first at line 1)")]


def test_syntax_error_has_line(tmp_path):
    p = write(tmp_path, "name: a\ntrain:\n  timesteps: [1, 2\nother: 3\n")
    with pytest.raises(SpecError) as exc:
        read_yaml(p)
    [err] = exc.value.errors
    assert err.file == str(p) and err.line == 4 and err.path == ""
    assert err.message


def test_bad_indentation_error_line(tmp_path):
    with pytest.raises(SpecError) as exc:
        read_yaml(write(tmp_path, "a: 1\nb:\n  c: 2\n d: 3\n"))
    assert exc.value.errors[0].line == 4


def test_missing_file(tmp_path):
    p = tmp_path / "nope.yaml"
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    [err] = exc.value.errors
    assert (err.file, err.line) == (str(p), None)
    assert str(err).startswith(f"{p}: cannot read file")


def test_directory_is_not_readable(tmp_path):
    with pytest.raises(SpecError) as exc:
        read_yaml(tmp_path)
    assert exc.value.errors[0].line is None


def test_not_utf8(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_bytes(b"a: 1\nb: \xff\xfe\n")
    with pytest.raises(SpecError) as exc:
        read_yaml(p)
    assert issues(exc)[0][:2] == (2, "")
    assert "UTF-8" in str(exc.value)


@pytest.mark.parametrize("text", ["", "# only a comment\n", "---\n"])
def test_empty_file(tmp_path, text):
    with pytest.raises(SpecError, match="empty"):
        read_yaml(write(tmp_path, text))


@pytest.mark.parametrize("text", ["- a\n- b\n", "just a string\n", "42\n"])
def test_top_level_not_mapping(tmp_path, text):
    with pytest.raises(SpecError, match="mapping") as exc:
        read_yaml(write(tmp_path, text))
    assert exc.value.errors[0].line == 1


def test_multiple_documents_rejected(tmp_path):
    with pytest.raises(SpecError) as exc:
        read_yaml(write(tmp_path, "a: 1\n---\nb: 2\n"))
    assert exc.value.errors[0].line == 2


# --- overrides ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("3", 3),
        ("-7", -7),
        ("1e-3", 0.001),
        ("3e5", 300000.0),
        ("-2.5e+2", -250.0),
        ("0.5", 0.5),
        ("[1, 2]", [1, 2]),
        ("{a: 1}", {"a": 1}),
        ("true", True),
        ("false", False),
        ("abc", "abc"),
        ("'3'", "3"),
        ("null", None),
        ("", None),
        ("#fff", "#fff"),
        ("hello world", "hello world"),
    ],
)
def test_yaml_scalar(text, value):
    got = yaml_scalar(text)
    assert got == value and type(got) is type(value)


def test_yaml_scalar_malformed():
    with pytest.raises(ValueError):
        yaml_scalar("[1, 2")


def test_apply_overrides_returns_new_dict():
    data = {
        "train": {"timesteps": 1},
        "avatars": [{"dwell": 0.1}, {"dwell": 0.2}],
        "reward": {"features": {}},
    }
    out = apply_overrides(
        data,
        [
            "train.timesteps=200000",
            "avatars.1.dwell=0.3",
            "reward.features.time.weight=-0.5",
            "train.lr=1e-3",
            "tags=[a, b]",
            "train.flag=true",
        ],
    )
    assert out == {
        "train": {"timesteps": 200000, "lr": 0.001, "flag": True},
        "avatars": [{"dwell": 0.1}, {"dwell": 0.3}],
        "reward": {"features": {"time": {"weight": -0.5}}},
        "tags": ["a", "b"],
    }
    assert data["train"] == {"timesteps": 1} and data["avatars"][1] == {"dwell": 0.2}


def test_value_may_contain_equals():
    assert apply_overrides({}, ["name=a=b"]) == {"name": "a=b"}


@pytest.mark.parametrize(
    ("override", "fragment"),
    [
        ("avatars.5.dwell=0.3", "not an index"),
        ("avatars.x=1", "not an index"),
        ("train.timesteps.value=3", "cannot descend into 'train.timesteps'"),
        ("train.timesteps", "expected dotted.path=value"),
        ("train..x=1", "expected dotted.path=value"),
        ("train.x=[1, 2", "invalid value"),
    ],
)
def test_override_errors(override, fragment):
    data = {"train": {"timesteps": 1}, "avatars": [{"dwell": 0.1}]}
    with pytest.raises(SpecError) as exc:
        apply_overrides(data, [override], source="--set")
    [err] = exc.value.errors
    assert (err.file, err.line) == ("--set", None)
    assert override in err.message and fragment in err.message


def test_all_override_errors_reported():
    with pytest.raises(SpecError) as exc:
        apply_overrides({"a": [1]}, ["a.3=1", "b", "a.0.x=2"], source="cli")
    assert [e.file for e in exc.value.errors] == ["cli"] * 3


def test_load_model_with_overrides(tmp_path):
    task = load_model(
        write(tmp_path, GOOD),
        Task,
        ["train.timesteps=200000", "avatars.0.dwell=0.3", "target.radius=1e-3"],
    )
    assert task.train.timesteps == 200000
    assert task.avatars[0].dwell == 0.3
    assert task.target.radius == 0.001


def test_errors_from_overridden_fields_blame_set(tmp_path):
    p = write(tmp_path, GOOD + "zzz: 1\n")
    with pytest.raises(SpecError) as exc:
        load_model(p, Task, ["train.timesteps=lots", "train.batch_siz=8", "avatars=[{name: c}]"])
    errs = exc.value.errors
    assert [(e.file, e.line, e.path) for e in errs] == [
        (str(p), 17, "zzz"),
        ("--set", None, "train.timesteps"),
        ("--set", None, "train.batch_siz"),
        ("--set", None, "avatars.0.pos"),
    ]
    assert "train.timesteps=lots" in errs[1].message
    assert "did you mean 'batch_size'?" in errs[2].message
    assert str(errs[3]).startswith("--set: avatars.0.pos: missing required field 'pos'")


def test_spec_issue_str():
    assert str(SpecIssue("f.yaml", 3, "a.b", "bad")) == "f.yaml:3: a.b: bad"
    assert str(SpecIssue("f.yaml", None, "a.b", "bad")) == "f.yaml: a.b: bad"
    assert str(SpecIssue("f.yaml", 3, "", "bad")) == "f.yaml:3: bad"
    err = SpecError([SpecIssue("f", 1, "", "x"), SpecIssue("f", 2, "p", "y")])
    assert str(err) == "f:1: x\nf:2: p: y"


def test_override_does_not_leak_through_yaml_alias(tmp_path):
    data, _ = read_yaml(write(tmp_path, "a: &x {v: 1}\nb: *x\n"))
    out = apply_overrides(data, ["b.v=2"])
    assert out == {"a": {"v": 1}, "b": {"v": 2}}


def test_override_into_null_is_an_error():
    with pytest.raises(SpecError, match="cannot descend into 'eval': it is null"):
        apply_overrides({"eval": None}, ["eval.episodes=3"])


def test_suggestion_uses_the_selected_union_member(tmp_path):
    p = write(tmp_path, GOOD.replace("  radius: 0.02\n", "  radius: 0.02\n  lenght: 1\n"))
    with pytest.raises(SpecError) as exc:
        load_model(p, Task)
    assert issues(exc) == [(16, "target.lenght", "unknown field 'lenght'")]  # 'length' belongs to Peg, not Ring


def _double(v: int) -> int:
    return v * 2


class Knob(BaseModel):
    model_config = CFG
    value: Annotated[int, AfterValidator(_double)] | Pos


def test_plain_union_markers_dropped(tmp_path):
    p = write(tmp_path, "value:\n  x: 1\n  y: bad\n")
    with pytest.raises(SpecError) as exc:
        load_model(p, Knob)
    assert issues(exc) == [
        (1, "value", "Input should be a valid integer"),
        (3, "value.y", issues(exc)[1][2]),
    ]
