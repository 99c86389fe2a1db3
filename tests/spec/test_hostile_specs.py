"""Hostile spec files: alias bombs, deep nesting, control characters, special files, oversized lists,
non-finite numbers and impossible time limits are refused quickly with one FILE:LINE: field: message line."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pytest
from typer.testing import CliRunner

from fastrl.cli import app
from fastrl.spec import SpecError, load_spec
from fastrl.spec.limits import LIMITS, MAX_SPEC_BYTES, MAX_YAML_DEPTH

SPECS = Path(__file__).resolve().parents[2] / "specs"
IC = (SPECS / "imagecentring.yaml").read_text(encoding="utf-8")
TL = (SPECS / "tracelines.yaml").read_text(encoding="utf-8")
LINE = "points: [[0.04, -0.04], [0.01, -0.01], [-0.01, 0.03], [-0.05, 0.04]]"
pytestmark = pytest.mark.timeout(60)


def laughs(indent: str = "") -> str:
    """Billion laughs: nine levels of nine aliases each, 9^9 strings once expanded."""
    text = f'{indent}a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]\n'
    for prev, name in zip("abcdefgh", "bcdefghi"):
        text += f"{indent}{name}: &{name} [{', '.join(['*' + prev] * 9)}]\n"
    return text


def sub(text: str, old: str, new: str) -> str:
    """text with its one occurrence of old replaced."""
    assert text.count(old) == 1, old
    return text.replace(old, new)


@dataclass
class Case:
    """A hostile spec text, and the line, field path and phrase of the one issue it must give."""

    id: str
    text: str | bytes
    line: int | None
    path: str
    phrase: str


def line_of(text: str, needle: str) -> int:
    """1-based line of the first line containing needle."""
    return next(n for n, line in enumerate(text.splitlines(), 1) if needle in line)


BOMB_UNKNOWN = IC + "junk:\n" + laughs("  ")
BOMB_DESCRIPTION = sub(IC, "description: Image centring", "description: " + "{" + laughs().replace("\n", ", ") + "}\n#")
BOMB_MERGE = (
    IC
    + "junk:\n  a: &a {x: 1, y: 2}\n"
    + "".join(f"  {n}: &{n} {{<<: [{', '.join(['*' + p] * 9)}], {n}: 1}}\n" for p, n in zip("abcdefgh", "bcdefghi"))
)
DEEP_FLOW = IC + "junk: " + "[" * 5000 + "]" * 5000 + "\n"
DEEP_BLOCK = IC + "junk:\n" + "".join(" " * (i + 1) + f"k{i}:\n" for i in range(600)) + " " * 601 + "end: 1\n"
DEEP_ALIAS = IC + "junk:\n  a0: &a0 [1]\n" + "".join(f"  a{i}: &a{i} [*a{i - 1}]\n" for i in range(1, 200))
RECURSIVE = IC + "junk: &j [1, *j]\n"
NUL = sub(IC, "name: imagecentring", "name: image\x00centring")
BELL = sub(IC, "description: Image", "description: \x07Image")
BINARY = IC.encode() + bytes(range(256))
TEN_K = "points: [" + ", ".join(f"[{0.05 * (-1) ** i:.3f}, {-0.05 + 1e-5 * i:.5f}]" for i in range(10_000)) + "]"
ZIGZAG = "points: [" + ", ".join(f"[{0.05 * (-1) ** i:.3f}, {-0.05 + 0.001 * i:.3f}]" for i in range(100)) + "]"
INDENT = sub(IC, "  radius: 0.12 ", "   radius: 0.12 ")
TAB = sub(IC, "  radius: 0.12 ", "\tradius: 0.12 ")
WEIGHT = "time:      {weight: -0.01}"

CASES = [
    Case("alias_bomb_unknown_key", BOMB_UNKNOWN, line_of(BOMB_UNKNOWN, "  f: &f"), "junk.f", "aliases (*name)"),
    Case("alias_bomb_description", BOMB_DESCRIPTION, 8, "description.f", "aliases (*name) are expanded"),
    Case("alias_bomb_merge_keys", BOMB_MERGE, line_of(BOMB_MERGE, "  f: &f"), "junk.f.<<", "aliases (*name)"),
    Case("deep_flow_lists", DEEP_FLOW, line_of(DEEP_FLOW, "junk:"), "", f"more than {MAX_YAML_DEPTH} levels"),
    Case("deep_block_mappings", DEEP_BLOCK, line_of(DEEP_BLOCK, " k30:"), "", f"more than {MAX_YAML_DEPTH} levels"),
    Case("deep_alias_chain", DEEP_ALIAS, line_of(DEEP_ALIAS, "a29:"), "junk.a30.0", "levels deep once aliases"),
    Case("recursive_alias", RECURSIVE, line_of(RECURSIVE, "junk:"), "junk.1", "refers to a list or mapping that"),
    Case("nul_character", NUL, line_of(NUL, "name: image"), "", "U+0000 is not allowed"),
    Case("control_character", BELL, line_of(BELL, "description:"), "", "U+0007 is not allowed"),
    Case("raw_binary_bytes", BINARY, IC.count("\n") + 2, "", "not valid UTF-8"),
    Case("too_large", IC + "#" * MAX_SPEC_BYTES + "\n", None, "", "file is too large"),
    Case("line_of_10000_points", sub(TL, LINE, TEN_K), line_of(TL, LINE), "task.line.points", "10,000 entries"),
    Case("line_too_many_avatars", sub(TL, LINE, ZIGZAG), line_of(TL, "line:"), "task.line", "avatars 0.01 m apart"),
    Case(
        "inf_weight",
        sub(IC, WEIGHT, "time: {weight: .inf}"),
        line_of(IC, WEIGHT),
        "reward.features.time.weight",
        "got .inf",
    ),
    Case(
        "nan_weight",
        sub(IC, WEIGHT, "time: {weight: .nan}"),
        line_of(IC, WEIGHT),
        "reward.features.time.weight",
        "got .nan",
    ),
    Case(
        "minus_inf_noise",
        sub(IC, "yaw_deg: 8, insertion", "yaw_deg: -.inf, insertion"),
        line_of(IC, "scope_noise:"),
        "episode.resets.scope_noise.yaw_deg",
        "-.inf",
    ),
    Case(
        "inf_as_text",
        sub(IC, WEIGHT, "time: {weight: inf}"),
        line_of(IC, WEIGHT),
        "reward.features.time.weight",
        "finite number",
    ),
    Case(
        "nan_param",
        sub(IC, "params: {max_speed: 0.08}", "params: {max_speed: .nan}"),
        line_of(IC, "params: {max_speed: 0.08}"),
        "reward.features.velocity.params.max_speed",
        "got .nan",
    ),
    Case(
        "huge_integer",
        sub(IC, "  seed: 0\n", "  seed: 100000000000000000000000000\n"),
        line_of(IC, "  seed: 0"),
        "train.seed",
        "too large",
    ),
    Case(
        "time_limit_below_one_step",
        sub(IC, "time_limit: 40", "time_limit: 0.01"),
        line_of(IC, "time_limit: 40"),
        "episode.time_limit",
        "one control step",
    ),
    Case(
        "time_limit_1e300",
        sub(IC, "time_limit: 40", "time_limit: 1e300"),
        line_of(IC, "time_limit: 40"),
        "episode.time_limit",
        "more than a day",
    ),
    Case(
        "time_limit_too_many_steps",
        sub(sub(IC, "time_limit: 40", "time_limit: 3600"), "control_hz: 20 ", "control_hz: 1000 "),
        line_of(IC, "time_limit: 40"),
        "episode.time_limit",
        "3,600,000 control steps, at most 1,000,000",
    ),
    Case(
        "indentation",
        INDENT,
        line_of(INDENT, "   radius:"),
        "",
        "indentation does not match the block that starts at line",
    ),
    Case("tab_indent", TAB, line_of(TAB, "radius: 0.12"), "", "a tab character: indent YAML with spaces only"),
    Case(
        "unclosed_quote",
        sub(IC, "name: imagecentring", 'name: "imagecentring'),
        7,
        "",
        "quoted text that starts at line 7",
    ),
    Case(
        "missing_colon",
        sub(IC, "  radius: 0.12 ", "  radius 0.12 "),
        line_of(IC, "  radius: 0.12 "),
        "",
        "neither 'key: value' nor a list item",
    ),
    Case("python_tag", sub(IC, "name: imagecentring", "name: !!python/object:os.system x"), 7, "", "tag"),
    Case(  # issue 42: MuJoCo's JSON step refused it, with no line or field
        "lone_surrogate",
        sub(IC, "name: lateral", 'name: "lat\\ud800"'),
        line_of(IC, "name: lateral"),
        "scene.portals.0.name",
        "holds \\ud800, half of a UTF-16 surrogate pair",
    ),
    Case(
        "lone_surrogate_key",
        sub(IC, "params: {max_speed: 0.08}", 'params: {"max\\udfff": 0.08}'),
        line_of(IC, "params: {max_speed: 0.08}"),
        "reward.features.velocity.params.max\udfff",
        "this key holds \\udfff",
    ),
    Case(
        "surrogate_pair_escaped_as_halves",
        sub(IC, "description: Image centring", 'description: "\\ud83d\\ude00 Image centring" #'),
        line_of(IC, "description: Image centring"),
        "description",
        "\\ud83d",
    ),
]


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_hostile_spec_is_one_clear_issue(tmp_path, case):
    """load_spec raises SpecError with one issue at the expected line and field, phrased plainly."""
    path = tmp_path / "spec.yaml"
    path.write_bytes(case.text if isinstance(case.text, bytes) else case.text.encode("utf-8"))
    with pytest.raises(SpecError) as exc:
        load_spec(path)
    [issue] = exc.value.errors
    assert (issue.file, issue.line, issue.path) == (str(path), case.line, case.path), str(issue)
    assert case.phrase in issue.message, str(issue)
    assert "\n" not in str(issue)


def test_yaml_messages_are_plain_sentences(tmp_path):
    """No PyYAML wording ('<block end>', 'mapping values') reaches the user for common slips."""
    slips = [
        INDENT,
        TAB,
        sub(IC, "name: imagecentring", "name: a: b"),
        sub(IC, "roll_deg: 20, cable_deg: 20}", "roll_deg: 20, cable_deg: 20"),
    ]
    for i, text in enumerate(slips):
        path = tmp_path / f"slip{i}.yaml"
        path.write_text(text, encoding="utf-8")
        with pytest.raises(SpecError) as exc:
            load_spec(path)
        [issue] = exc.value.errors
        assert issue.line is not None
        assert not any(w in issue.message for w in ("<block", "mapping values", "but found", "while parsing")), issue


def special_files(tmp_path: Path) -> list[tuple[Path, str]]:
    """A symlink loop, a FIFO and a folder named like specs, with the phrase each must give."""
    loop_a, loop_b = tmp_path / "loop_a.yaml", tmp_path / "loop_b.yaml"
    os.symlink(loop_b, loop_a)
    os.symlink(loop_a, loop_b)
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    return [(loop_a, "symbolic links"), (fifo, "not a regular file"), (folder, "a folder")]


def test_special_files_are_refused_without_blocking(tmp_path):
    """A symlink loop, a FIFO (which would block a plain open) and a folder: one issue each."""
    for path, phrase in special_files(tmp_path):
        with pytest.raises(SpecError) as exc:
            load_spec(path)
        [issue] = exc.value.errors
        assert str(issue).startswith(f"{path}: cannot read file") and phrase in str(issue)


HOSTILE_CLI = ["alias_bomb_unknown_key", "deep_flow_lists", "nul_character", "line_of_10000_points", "inf_weight"]
HOSTILE_CLI += ["time_limit_below_one_step", "indentation", "recursive_alias", "lone_surrogate"]


@pytest.mark.parametrize("command", ["check", "run"])
def test_cli_refuses_every_class_with_exit_2_and_one_line(tmp_path, command):
    """Through `fastrl check` and `fastrl run`: exit 2, one FILE:LINE: line per file, no traceback, no run."""
    cases = {c.id: c for c in CASES}
    files = []
    for name in HOSTILE_CLI:
        path = tmp_path / f"{name}.yaml"
        path.write_text(cases[name].text, encoding="utf-8")
        files.append(path)
    files += [p for p, _ in special_files(tmp_path)]
    files = files if command == "check" else files[::4]  # each `run` costs a second of imports
    runner = CliRunner()
    for path in files:
        args = [command, str(path)] + (["--runs", str(tmp_path / "runs"), "--no-progress"] if command == "run" else [])
        result = runner.invoke(app, args)
        assert result.exit_code == 2, (path, result.output)
        assert isinstance(result.exception, SystemExit), result.exception
        [line] = result.stderr.splitlines()
        assert line.startswith(f"{path}:") and "Traceback" not in result.output
    assert not (tmp_path / "runs").exists()


def test_limits_are_listed_for_the_docs():
    """The limits table names every limit once with its value."""
    names = [name for name, _, _ in LIMITS]
    assert len(names) == len(set(names)) and all(str(value) for _, value, _ in LIMITS)


def test_a_fifo_or_folder_as_an_organ_mesh_is_refused_at_its_line(tmp_path):
    """An organ's mesh that is a FIFO (MuJoCo would block reading it) or a folder: an issue at the mesh line."""
    text = (SPECS / "liver_tour.yaml").read_text(encoding="utf-8")
    os.mkfifo(tmp_path / "fifo.obj")
    (tmp_path / "folder.obj").mkdir()
    for name in ("fifo.obj", "folder.obj"):
        path = tmp_path / f"{name}.yaml"
        old = "left_lobe:   {centre"
        path.write_text(sub(text, old, f"left_lobe:   {{mesh: {name}, centre"), encoding="utf-8")
        with pytest.raises(SpecError) as exc:
            load_spec(path)
        [issue] = exc.value.errors
        assert (issue.line, issue.path) == (line_of(text, old), "scene.anatomy.left_lobe.mesh")
        assert issue.message == f"mesh {name} is not a regular file"
