"""The `fastrl` command line: check, schema, compile, --version; exit codes and messages."""

from __future__ import annotations

import json
import shutil
import subprocess
import tomllib
from importlib import metadata
from pathlib import Path

import mujoco
import pytest
from typer.testing import CliRunner

import fastrl
import fastrl.model.loaded
from fastrl.cli import app
from fastrl.model import compile_task
from fastrl.spec import SpecError, load_spec

SPECS = Path(__file__).resolve().parents[2] / "specs"
BAD = Path(__file__).resolve().parents[1] / "fixtures" / "bad_specs"
GOOD = [SPECS / "imagecentring.yaml", SPECS / "periscoping.yaml", SPECS / "tracelines.yaml"]
runner = CliRunner()


def invoke(*args):
    """Run the app in-process with string arguments."""
    return runner.invoke(app, [str(a) for a in args])


def test_version():
    """--version prints pyproject's distribution name and version (the installed metadata's, where installed)."""
    project = tomllib.loads((SPECS.parent / "pyproject.toml").read_text())["project"]
    assert (fastrl.DISTRIBUTION, fastrl.__version__) == (project["name"], project["version"])
    try:
        installed = metadata.version(project["name"])
    except metadata.PackageNotFoundError:  # a source tree on PYTHONPATH, or metadata under an older name
        installed = None
    result = invoke("--version")
    assert result.exit_code == 0
    name, version, rest = result.stdout.strip().split(" ", 2)
    assert (name, version) == (project["name"], installed or project["version"])
    assert rest.startswith("(import name fastrl") and ("without installed metadata" in rest) == (installed is None)


def test_no_args_shows_help():
    """Without a command the help lists the commands."""
    result = invoke()
    assert "check" in result.output and "compile" in result.output and "schema" in result.output


def test_check_good_specs():
    """Good specs: exit 0, one ok line each with kind, subtask count and action mode."""
    result = invoke("check", *GOOD)
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines == [
        f"ok  {p}  ({load_spec(p).task.kind}, {len(compile_task(load_spec(p)).targets)} subtasks, discrete)"
        for p in GOOD
    ]
    assert "trace_lines, 13 subtasks" in lines[2]
    assert result.stderr == ""


def test_check_bad_spec():
    """A bad spec: exit 2, every FILE:LINE message on stderr, no traceback."""
    path = BAD / "several_errors.yaml"
    result = invoke("check", path)
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 6
    assert all(line.startswith(f"{path}:") for line in lines)
    assert f"{path}:9: scope.optics_deg: Input should be 0, 30 or 70" in lines
    assert "Traceback" not in result.output
    assert result.stdout == ""


def test_check_refuses_term_parameters_outside_their_domain(tmp_path):
    """Issue 42: `margin: 0` (and `--set` of -0.02) passed `fastrl check`; now FILE:LINE or --set, exit 2."""
    text = (SPECS / "imagecentring.yaml").read_text(encoding="utf-8")
    path = tmp_path / "margin.yaml"
    path.write_text(text.replace("distance:  {weight: 0.0}", "distance:  {weight: 1.0, params: {margin: 0}}"))
    line = next(n for n, t in enumerate(path.read_text().splitlines(), 1) if "margin: 0" in t)
    result = invoke("check", path)
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert result.stderr.startswith(f"{path}:{line}: reward.features.distance.params.margin: must be a number from")
    result = invoke("check", SPECS / "imagecentring.yaml", "--set", "reward.features.distance.params.margin=-0.02")
    assert result.exit_code == 2 and result.stderr.startswith("--set: reward.features.distance.params.margin:")


def test_check_mixed_files_checks_all():
    """One bad file among good ones: exit 2, its message shown, the good ones still reported ok."""
    bad = BAD / "duplicate_key.yaml"
    result = invoke("check", GOOD[0], bad, GOOD[2])
    assert result.exit_code == 2
    assert [line.split()[1] for line in result.stdout.splitlines()] == [str(GOOD[0]), str(GOOD[2])]
    assert result.stderr.strip() == f"{bad}:8: duplicate key 'radius' (first at line 5)"


@pytest.mark.parametrize("name", ["empty.yaml", "syntax_error.yaml", "missing.yaml"])
def test_check_unreadable_is_one_line(name):
    """An empty, unparsable or missing file is exit 2 with a one-line message naming it."""
    result = invoke("check", BAD / name)
    assert result.exit_code == 2
    [line] = result.stderr.splitlines()
    assert line.startswith(f"{BAD / name}")
    assert "Traceback" not in result.output


def test_check_set_override():
    """--set applies to the spec; a breaking override exits 2 and names --set."""
    assert (
        invoke("check", GOOD[0], "--set", "task.cue.dwell=1.0", "--set", "actions.mode=continuous")
        .stdout.strip()
        .endswith("(image_centring, 5 subtasks, continuous)")
    )
    result = invoke("check", GOOD[0], "--set", "scope.portal=nowhere")
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        "--set: scope.portal: no portal named 'nowhere' (portals: lateral, medial, "
        "superior) (from --set 'scope.portal=nowhere')"
    )
    malformed = invoke("check", GOOD[0], "--set", "novalue")
    assert malformed.exit_code == 2
    assert malformed.stderr.startswith("--set: bad override 'novalue'")


def test_long_message_stays_one_line_and_line_100_is_a_number(tmp_path):
    """Messages print verbatim: no wrapping at 80 columns, ':100:' not turned into an emoji."""
    text = GOOD[0].read_text().replace("portal: lateral ", "portal: x ")
    before = next(i for i, line in enumerate(text.splitlines()) if "portal: x " in line)
    path = tmp_path / "long.yaml"
    path.write_text("#\n" * (99 - before) + text)  # puts `portal: x` on line 100
    with pytest.raises(SpecError) as exc:
        load_spec(path)
    [issue] = exc.value.errors
    assert issue.line == 100
    result = invoke("check", path)
    assert result.stderr.splitlines() == [str(issue)]
    assert len(str(issue)) > 80


def test_check_compile_error(monkeypatch):
    """A MuJoCo compile error is reported like a spec error: exit 2, one line, no traceback."""

    def broken(spec):
        raise ValueError("Error: mesh 'dome' not found\nElement name 'x', id 3")

    monkeypatch.setattr(fastrl.model.loaded, "compile_task", broken)
    result = invoke("check", GOOD[0])
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        f"{GOOD[0]}: MuJoCo cannot compile the model: Error: mesh 'dome' not found Element name 'x', id 3"
    )


def test_schema(tmp_path):
    """schema prints valid JSON to stdout, or writes it with -o."""
    result = invoke("schema")
    assert result.exit_code == 0
    schema = json.loads(result.stdout)
    assert {"scene", "scope", "task", "reward"} <= set(schema["properties"])
    out = tmp_path / "schema.json"
    assert invoke("schema", "-o", out).exit_code == 0
    assert json.loads(out.read_text()) == schema


def test_compile_writes_loadable_mjcf(tmp_path):
    """compile writes MJCF that MuJoCo loads with compile_task's sizes, and prints them."""
    out = tmp_path / "model.xml"
    result = invoke("compile", GOOD[2], "-o", out)
    assert result.exit_code == 0, result.output
    loaded = mujoco.MjModel.from_xml_path(str(out))
    ref = compile_task(load_spec(GOOD[2])).model
    sizes = ("nbody", "njnt", "ngeom", "nu")
    assert [getattr(loaded, s) for s in sizes] == [getattr(ref, s) for s in sizes]
    assert loaded.opt.timestep == ref.opt.timestep
    assert (
        f"nbody {ref.nbody}, njnt {ref.njnt}, ngeom {ref.ngeom}, nu {ref.nu}, timestep {ref.opt.timestep:g} s"
        in result.stdout
    )


def test_compile_bad_spec_and_bad_output(tmp_path):
    """compile: a bad spec exits 2 without writing; an unwritable output exits 1 with one line."""
    out = tmp_path / "model.xml"
    result = invoke("compile", BAD / "several_errors.yaml", "-o", out)
    assert result.exit_code == 2 and len(result.stderr.splitlines()) == 6
    assert not out.exists()
    result = invoke("compile", GOOD[0], "-o", tmp_path / "no" / "dir" / "model.xml")
    assert result.exit_code == 1
    assert result.stderr.startswith("cannot write") and "Traceback" not in result.output


def test_console_script(tmp_path):
    """The installed `fastrl` script: ok for a good spec, FILE:LINE on stderr for a bad one."""
    exe = shutil.which("fastrl")
    assert exe, "the fastrl console script is not installed"
    bad = BAD / "syntax_error.yaml"
    proc = subprocess.run(
        [exe, "check", str(GOOD[1]), str(bad)],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert proc.stdout.startswith(f"ok  {GOOD[1]}  (periscoping, 5 subtasks, discrete)")
    assert proc.stderr.startswith(f"{bad}:6: the list '[...]' opened at line 6 is not closed with ']'")
    assert "Traceback" not in proc.stderr and "\x1b[" not in proc.stdout  # no colour codes in a pipe


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (("eval", "--expert", "tracelines", "--episodes", "0"), "--episodes"),
        (("demos", "--expert", "tracelines", "-n", "0"), "-n"),
        (("demos", "--expert", "tracelines", "-n", "1", "-o", "{file}"), "a file is there"),
        (("score", "{folder}", "--spec", "tracelines", "--references", "0"), "--references"),
        (("score", "{folder}", "--spec", "tracelines", "-o", "{tmp}/r.json"), "no trajectory could be"),
        (("render-video", "{folder}", "-o", "{tmp}/v.mp4"), "wrote 0 videos"),
    ],
)
def test_out_of_domain_options_exit_2_with_one_message(tmp_path, args, says):
    """A count below one, a file where a folder goes, a folder with nothing in it: exit 2, a message, no traceback."""
    (tmp_path / "empty").mkdir()
    (tmp_path / "a.txt").write_text("not a folder")
    where = {"file": tmp_path / "a.txt", "folder": tmp_path / "empty", "tmp": tmp_path}
    result = invoke(*(a.format(**where) for a in args))
    assert result.exit_code == 2, result.output
    assert says in result.output and "Traceback" not in result.output
    assert (tmp_path / "a.txt").read_text() == "not a folder"
