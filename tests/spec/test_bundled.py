"""The bundled specs are package data: in the wheel, found through importlib.resources, usable by name."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from importlib import resources
from pathlib import Path

import gymnasium as gym
import pytest
from typer.testing import CliRunner

import fastrl
from fastrl.cli import app
from fastrl.spec import SpecError, load_spec, spec_hash

ROOT = Path(__file__).resolve().parents[2]


def package_specs() -> dict[str, bytes]:
    """The bundled spec files as importlib.resources sees them, by file name."""
    folder = resources.files("fastrl").joinpath("specs")
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.name.endswith(".yaml")}


def test_every_registered_task_is_package_data_and_the_top_level_folder_is_the_same_files():
    specs = package_specs()
    assert {f"{name}.yaml" for name in fastrl.TASK_IDS.values()} <= set(specs)
    top = {p.name: p.read_bytes() for p in (ROOT / "specs").glob("*.yaml")}
    assert top == specs  # one copy: specs/ is the package's folder, as users see it
    assert fastrl.SPECS_DIR.samefile(ROOT / "specs")


@pytest.mark.parametrize("name", sorted(fastrl.TASK_IDS.values()))
def test_a_bundled_name_makes_the_same_env_as_its_file(name):
    by_name = fastrl.make(name)
    by_file = fastrl.make(ROOT / "specs" / f"{name}.yaml")
    assert spec_hash(by_name.task_spec) == spec_hash(by_file.task_spec)
    assert by_name.observation_space == by_file.observation_space
    assert by_name.action_space == by_file.action_space


def test_an_unknown_name_names_the_bundled_specs_without_a_traceback(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no specs/ folder here: names come from the package
    with pytest.raises(SpecError) as exc:
        load_spec("tracelinez")
    assert "no bundled spec" in str(exc.value) and "tracelines" in str(exc.value)
    res = CliRunner().invoke(app, ["check", "tracelinez", "tracelines"])
    assert res.exit_code == 2 and "Traceback" not in res.output
    assert "tracelinez: cannot read file" in res.output and "ok  tracelines" in res.output
    assert gym.make("fastrl/TraceLines-v0").unwrapped.task_spec.name == "tracelines"


def test_a_file_of_a_bundled_name_in_the_working_folder_wins_a_folder_does_not(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("imagecentring").mkdir()  # e.g. in runs/, where every spec has its folder
    assert load_spec("imagecentring").name == "imagecentring"
    with pytest.raises(SpecError, match="it is a folder"):
        load_spec(tmp_path)
    text = (ROOT / "specs" / "tracelines.yaml").read_text()
    Path("tracelines").write_text(text.replace("time_limit: ", "time_limit: 1", 1))
    assert spec_hash(load_spec("tracelines")) != spec_hash(load_spec(fastrl.spec_path("tracelines")))


def test_the_wheel_holds_every_bundled_spec(tmp_path):
    pytest.importorskip("setuptools", minversion="68")
    src = tmp_path / "src"
    shutil.copytree(ROOT / "fastrl", src / "fastrl", ignore=shutil.ignore_patterns("__pycache__"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    cmd = [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation", "-w", tmp_path, src]
    subprocess.run([str(c) for c in cmd], check=True, capture_output=True, timeout=300)
    (wheel,) = tmp_path.glob("*.whl")
    with zipfile.ZipFile(wheel) as z:
        held = {n.removeprefix("fastrl/specs/"): z.read(n) for n in z.namelist() if n.startswith("fastrl/specs/")}
    assert held == package_specs()


def test_an_installed_copy_inside_another_repository_reports_no_commit(tmp_path):
    """meta.json's git_commit is fastrl's source tree, never a repository a venv happens to sit in."""
    site = tmp_path / "project" / ".venv" / "site-packages"
    shutil.copytree(ROOT / "fastrl", site / "fastrl", ignore=shutil.ignore_patterns("__pycache__"))
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-C", str(tmp_path / "project")]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "commit", "-q", "--allow-empty", "-m", "someone else's project"], check=True)
    code = "from fastrl.runner.runs.rundir import git_commit; print(git_commit())"
    env = {**os.environ, "PYTHONPATH": str(site)}
    proc = subprocess.run([sys.executable, "-c", code], env=env, cwd=site, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "None"
    from fastrl.runner.runs.rundir import git_commit

    if (ROOT / ".git").exists():  # a checkout (not an unpacked sdist): its own commit
        head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True)
        assert git_commit().split("-")[0] == head.stdout.strip()
