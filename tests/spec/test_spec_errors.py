"""Malformed task specs: every problem is reported with its line, field path and a clear message."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import pytest

from fastrl.spec import SpecError, SpecIssue, json_schema, load_spec

SPECS = Path(__file__).resolve().parents[2] / "specs"
BAD = Path(__file__).resolve().parents[1] / "fixtures" / "bad_specs"
REAL = ["imagecentring", "periscoping", "tracelines"]


def edit(spec: str, old: str, new: str) -> str:
    """Text of a real spec with one unique snippet replaced."""
    text = (SPECS / f"{spec}.yaml").read_text(encoding="utf-8")
    assert text.count(old) == 1, f"{old!r} is not unique in {spec}.yaml"
    return text.replace(old, new)


def line_of(text: str, needle: str) -> int:
    """1-based number of the only line of text that contains needle."""
    hits = [n for n, line in enumerate(text.splitlines(), 1) if needle in line]
    assert len(hits) == 1, f"{needle!r} is on lines {hits}"
    return hits[0]


def errors(path: Path) -> list[SpecIssue]:
    """The issues load_spec raises for a file (it must raise)."""
    with pytest.raises(SpecError) as exc:
        load_spec(path)
    return exc.value.errors


@dataclass
class Case:
    """A one-snippet edit of a real spec and the single issue it must produce."""

    id: str
    spec: str
    old: str
    new: str
    marker: str  # text on the line the issue must point at
    path: str
    phrase: str


CASES = [
    Case(
        "unknown_top_level",
        "imagecentring",
        "\nevaluate:",
        "\nevalute:",
        "evalute:",
        "evalute",
        "unknown field 'evalute' (did you mean 'evaluate'?)",
    ),
    Case(
        "unknown_nested",
        "imagecentring",
        "  fov_deg: 80 ",
        "  fov_dge: 80 ",
        "fov_dge",
        "scope.fov_dge",
        "unknown field 'fov_dge' (did you mean 'fov_deg'?)",
    ),
    Case(
        "unknown_in_flow_mapping",
        "periscoping",
        "start: {pitch_deg: 0,",
        "start: {pich_deg: 0,",
        "pich_deg",
        "scope.start.pich_deg",
        "did you mean 'pitch_deg'?",
    ),
    Case(
        "wrong_type_int",
        "imagecentring",
        "  substeps: 5 ",
        "  substeps: ten ",
        "substeps: ten",
        "episode.substeps",
        "valid integer",
    ),
    Case(
        "wrong_type_number",
        "tracelines",
        "  time_limit: 30",
        "  time_limit: [30]",
        "time_limit",
        "episode.time_limit",
        "valid number",
    ),
    Case(
        "optics_not_allowed",
        "imagecentring",
        "optics_deg: 30 ",
        "optics_deg: 45 ",
        "optics_deg: 45",
        "scope.optics_deg",
        "0, 30 or 70",
    ),
    Case(
        "plate_target_outside_dome",
        "imagecentring",
        "at: [0.01, -0.06]",
        "at: [0.2, -0.06]",
        "at: [0.2, -0.06]",
        "task.avatars.2.at",
        "is outside the dome",
    ),
    Case(
        "dome_target_elevation",
        "imagecentring",
        "at: [120, 40]",
        "at: [120, 95]",
        "at: [120, 95]",
        "task.avatars.3.at",
        "elevation 95.0 deg is outside the dome's inner surface",
    ),
    Case(
        "portal_elevation",
        "imagecentring",
        "azimuth: 90,  elevation: 45}",
        "azimuth: 90,  elevation: 89}",
        "elevation: 89",
        "scene.portals.2.elevation",
        "less than or equal to 85",
    ),
    Case(
        "line_point_outside_dome",
        "tracelines",
        "[-0.05, 0.04]]",
        "[-0.15, 0.04]]",
        "[-0.15, 0.04]]",
        "task.line.points.3",
        "is outside the dome",
    ),
    Case(
        "portal_cannot_reach",
        "imagecentring",
        "at: [120, 40]",
        "at: [180, 10]",
        "at: [180, 10]",
        "task.avatars.3.at",
        "portal 'lateral' cannot reach this target",
    ),
    Case(
        "unknown_scope_portal",
        "imagecentring",
        "portal: lateral ",
        "portal: lateal ",
        "portal: lateal",
        "scope.portal",
        "no portal named 'lateal' (portals: lateral, medial, superior)",
    ),
    Case(
        "negative_centring",
        "imagecentring",
        "centring_deg: 8 ",
        "centring_deg: -3 ",
        "centring_deg: -3",
        "task.cue.centring_deg",
        "greater than or equal to 0.000001",  # a microdegree: the cue potential divides by it
    ),
    Case(
        "decreasing_distance",
        "imagecentring",
        "distance: [0.02, 0.05]",
        "distance: [0.05, 0.02]",
        "distance: [0.05, 0.02]",
        "task.cue.distance",
        "distance range must be increasing",
    ),
    Case(
        "decreasing_insertion",
        "periscoping",
        "insertion: [0.01, 0.15]",
        "insertion: [0.15, 0.01]",
        "insertion: [0.15, 0.01]",
        "scope.insertion",
        "insertion range must be increasing",
    ),
    Case(
        "missing_field",
        "imagecentring",
        "{surface: plate, at: [0.0, 0.0],    heading_deg: 90}",
        "{surface: plate, heading_deg: 90}",
        "{surface: plate, heading_deg: 90}",
        "task.avatars.0.at",
        "missing required field 'at'",
    ),
    Case(
        "unknown_feature",
        "imagecentring",
        "angle:     {weight: 0.0}",
        "angel:     {weight: 0.0}",
        "angel:",
        "reward.features.angel",
        "unknown reward feature 'angel'",
    ),
    Case(
        "feature_param_unknown",
        "imagecentring",
        "velocity:  {weight: -0.1, params: {max_speed: 0.08}}",
        "velocity:  {weight: -1, params: {max_sped: 0.1}}",
        "max_sped",
        "reward.features.velocity.params.max_sped",
        "'velocity' takes no parameter 'max_sped' (it takes: max_speed)",
    ),
    Case(
        "feature_param_type",
        "tracelines",
        "params: {scale: 0.005}",
        "params: {scale: narrow}",
        "scale: narrow",
        "reward.features.line_deviation.params.scale",
        "must be a number from 1e-06 to 1 (a length in m, above zero), got 'narrow'",
    ),
    Case(
        "feature_margin_zero",  # issue 42: passed the type check, then divided by zero outside the band
        "imagecentring",
        "distance:  {weight: 0.0}",
        "distance:  {weight: 1.0, params: {margin: 0}}",
        "margin: 0",
        "reward.features.distance.params.margin",
        "must be a number from 1e-06 to 1 (a length in m, above zero), got 0",
    ),
    Case(
        "feature_margin_negative",
        "imagecentring",
        "distance:  {weight: 0.0}",
        "distance:  {weight: 1.0, params: {margin: -0.02}}",
        "margin: -0.02",
        "reward.features.distance.params.margin",
        "got -0.02",
    ),
    Case(
        "feature_speed_bool",
        "imagecentring",
        "velocity:  {weight: -0.1, params: {max_speed: 0.08}}",
        "velocity:  {weight: -0.1, params: {max_speed: yes}}",
        "max_speed",
        "reward.features.velocity.params.max_speed",
        "must be a number from 1e-06 to 100 (a speed in m/s, above zero), got True",
    ),
    Case(
        "unknown_observation_term",
        "periscoping",
        "  extra: [contact, elapsed]",
        "  extra: [contact, bogus]",
        "extra:",
        "observation.extra.1",
        "unknown observation term 'bogus'",
    ),
    Case(
        "trace_lines_without_line",
        "imagecentring",
        "kind: image_centring",
        "kind: trace_lines",
        "task:",
        "task",
        "trace_lines needs a 'line'",
    ),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_malformed_spec(tmp_path, case):
    """One edit of a real spec gives one issue, at the edited line, with its path and message."""
    text = edit(case.spec, case.old, case.new)
    path = tmp_path / f"{case.id}.yaml"
    path.write_text(text, encoding="utf-8")
    [issue] = errors(path)
    assert (issue.file, issue.line, issue.path) == (
        str(path),
        line_of(text, case.marker),
        case.path,
    )
    assert case.phrase in issue.message
    assert str(issue) == f"{path}:{issue.line}: {case.path}: {issue.message}"


def test_yaml_syntax_error():
    """A YAML syntax error is one issue at the broken line."""
    path = BAD / "syntax_error.yaml"
    [issue] = errors(path)
    assert issue.line == line_of(path.read_text(), "at: [0.0, 0.0}")
    assert issue.message.startswith("the list '[...]' opened at line") and "not closed with ']'" in issue.message


def test_duplicate_key():
    """A repeated key is an error naming both lines, not a silent overwrite."""
    path = BAD / "duplicate_key.yaml"
    text = path.read_text()
    first, second = [n for n, line in enumerate(text.splitlines(), 1) if line.startswith("  radius:")]
    [issue] = errors(path)
    assert issue.line == second
    assert issue.message == f"duplicate key 'radius' (first at line {first})"


@pytest.mark.parametrize(
    ("name", "phrase"),
    [
        ("empty.yaml", "file is empty"),
        ("not_a_mapping.yaml", "top level must be a mapping, got list"),
    ],
)
def test_no_mapping(name, phrase):
    """An empty file or a top-level list is one clear issue."""
    [issue] = errors(BAD / name)
    assert phrase in issue.message
    assert issue.line == (None if name == "empty.yaml" else 2)  # the list starts after the comment


def test_empty_text(tmp_path):
    """A zero-byte file is reported as empty, without a line."""
    path = tmp_path / "zero.yaml"
    path.write_text("")
    [issue] = errors(path)
    assert (issue.line, issue.message) == (None, "file is empty (expected a mapping of fields)")


def test_missing_and_binary_file(tmp_path):
    """A missing file and a non-UTF-8 file are issues, not OSError or UnicodeDecodeError."""
    [missing] = errors(tmp_path / "nope.yaml")
    assert missing.message.startswith("cannot read file")
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"name: x\n\xff\xfe\n")
    [issue] = errors(binary)
    assert (issue.line, "not valid UTF-8" in issue.message) == (2, True)


def test_several_errors_all_reported():
    """Every problem in a file is reported, in line order, each with its own line and path."""
    path = BAD / "several_errors.yaml"
    text = path.read_text()
    expected = [
        ("name: several", "name", "should match pattern"),
        ("radius: 2.0", "scene.radius", "less than or equal to 0.5"),
        ("portals: []", "scene.portals", "at least 1 item"),
        ("optics_deg: 45", "scope.optics_deg", "0, 30 or 70"),
        ("dwell: -1", "task.cue.dwell", "greater than or equal to 0"),
        ("speed:", "reward.features.speed", "unknown reward feature 'speed'"),
    ]
    got = errors(path)
    assert [(i.line, i.path) for i in got] == [(line_of(text, m), p) for m, p, _ in expected]
    for issue, (_, _, phrase) in zip(got, expected):
        assert phrase in issue.message


def test_override_error_names_set(tmp_path):
    """A bad --set override is blamed on --set, with the override text."""
    with pytest.raises(SpecError) as exc:
        load_spec(SPECS / "imagecentring.yaml", ["task.cue.dwell=-2"])
    [issue] = exc.value.errors
    assert (issue.file, issue.line, issue.path) == ("--set", None, "task.cue.dwell")
    assert "(from --set 'task.cue.dwell=-2')" in issue.message


@pytest.mark.parametrize("spec", ["loose_bodies", "triangulation"])
def test_recorded_starts_are_refused_where_the_scope_alone_does_not_replay_a_state(spec):
    """Recorded starts replay the scope's poses: a task with loose bodies or instruments is told so, at the field."""
    with pytest.raises(SpecError) as exc:
        load_spec(SPECS / f"{spec}.yaml", ["irl.algorithm=airl", "irl.generator.recorded_starts=0.5"])
    [issue] = exc.value.errors
    assert issue.path == "irl.generator.recorded_starts" and "instruments or loose bodies" in issue.message
    assert load_spec(SPECS / "liver_tour.yaml").irl.generator.recorded_starts == 0.25  # the one spec that asks


@pytest.mark.parametrize("name", REAL)
def test_real_specs_load(name):
    """The bundled specs are valid."""
    spec = load_spec(SPECS / f"{name}.yaml")
    assert spec.name == name


def test_json_schema():
    """The JSON Schema lists the top-level sections, forbids unknown keys and serialises."""
    schema = json_schema()
    assert set(schema["properties"]) == {
        "name",
        "description",
        "scene",
        "scope",
        "instruments",
        "task",
        "episode",
        "actions",
        "observation",
        "reward",
        "train",
        "irl",
        "study",
        "evaluate",
    }
    assert set(schema["required"]) == {"name", "scene", "scope", "task", "reward"}
    assert schema["additionalProperties"] is False
    assert json.loads(json.dumps(schema)) == schema


def test_irl_section_errors_name_the_field(tmp_path):
    """Unknown algorithms and BC on a SAC generator are spec errors with their field."""
    from fastrl.spec import SpecError, load_spec

    with pytest.raises(SpecError) as e:
        load_spec(SPECS / "tracelines.yaml", ["irl.algorithm=maxent"])
    assert "irl.algorithm" in str(e.value)
    with pytest.raises(SpecError) as e:
        load_spec(SPECS / "tracelines.yaml", ["irl.algorithm=bc", "train.algo=SAC", "actions.mode=continuous"])
    assert "irl.algorithm" in str(e.value) and "PPO" in str(e.value)
    with pytest.raises(SpecError) as e:
        load_spec(SPECS / "tracelines.yaml", ["irl.discriminator.spectral=true"])
    assert "spectral_norm" in str(e.value)  # did you mean
    with pytest.raises(SpecError) as e:
        load_spec(SPECS / "tracelines.yaml", ["irl.discriminator.ignore=[elapsed, camera_position]"])
    assert "irl.discriminator.ignore.1" in str(e.value) and "camera_position" in str(e.value)
    with pytest.raises(SpecError) as e:
        load_spec(SPECS / "tracelines.yaml", ["irl.discriminator.reward_ignore=[clock]"])
    assert "irl.discriminator.reward_ignore.0" in str(e.value) and "'clock' is not observed" in str(e.value)
    with pytest.raises(SpecError) as e:
        load_spec(SPECS / "tracelines.yaml", ["irl.discriminator.gradient_penalty=-1"])
    assert "irl.discriminator.gradient_penalty" in str(e.value)
    with pytest.raises(SpecError) as e:
        load_spec(SPECS / "tracelines.yaml", ["irl.discriminator.ranking_noise=[0, 1.5]"])
    assert "irl.discriminator.ranking_noise.1" in str(e.value)
