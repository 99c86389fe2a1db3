"""Specs saved in the 0.2 layout (run folders, trajectories and datasets carry them) read as today's specs."""

from pathlib import Path

import numpy as np
import pytest
import yaml

import fastrl
from fastrl.spec import SpecError, TaskSpec, load_spec, spec_hash, task_hash
from fastrl.spec.migrate import PORTAL_NOISE

SPECS = Path(fastrl.__file__).parent / "specs"
CONTEXT = {"base": SPECS}


def in_old_layout(data: dict) -> dict:
    """Spec data written back as 0.2 wrote it: noise in the starts, jitter in the task, no declared resets."""
    if "study" in data:
        data["experiment"] = data.pop("study")
    resets = data["episode"].pop("resets", {})
    data["episode"].pop("terminations", None)
    scope = resets.get("scope_noise", {})
    data["scope"]["start"]["noise"] = [scope.get(k, 0.0) for k in PORTAL_NOISE]
    for instrument in data.get("instruments", []):
        noise = resets.get("instrument_noise", {})
        instrument.setdefault("start", {})["noise"] = [noise.get(k, 0.0) for k in PORTAL_NOISE[:4]]
    jitter = resets.get("avatar_jitter")
    if jitter:
        data["task"]["jitter"] = [jitter.get("plate", 0.0), jitter.get("dome", 0.0)]
    return data


@pytest.mark.parametrize("name", sorted(p.stem for p in SPECS.glob("*.yaml")))
def test_a_spec_saved_in_the_old_layout_is_the_same_spec(name):
    today = load_spec(name)
    old = in_old_layout(yaml.safe_load((SPECS / f"{name}.yaml").read_text()))
    assert "resets" not in old["episode"] and "noise" in old["scope"]["start"] and "study" not in old
    again = TaskSpec.model_validate(old, context=CONTEXT)
    assert again == today and spec_hash(again) == spec_hash(today) and task_hash(again) == task_hash(today)


def test_old_jitter_and_zero_noise_keep_their_draws():
    data = in_old_layout(yaml.safe_load((SPECS / "triangulation.yaml").read_text()))
    data["task"]["jitter"], data["scope"]["start"]["noise"] = [0.01, 8], [0, 0, 0, 0, 0]
    spec = TaskSpec.model_validate(data, context=CONTEXT)
    assert spec.episode.resets["avatar_jitter"] == {"plate": 0.01, "dome": 8}
    assert set(spec.episode.resets["scope_noise"].values()) == {0}  # 0.2 drew it anyway: the draws stay in order
    assert "instrument_noise" in spec.episode.resets


def test_instruments_with_different_old_noise_are_refused_by_field(tmp_path):
    data = in_old_layout(yaml.safe_load((SPECS / "triangulation.yaml").read_text()))
    second = dict(data["instruments"][0], name="second", portal="superior")
    second["start"] = dict(second["start"], noise=[1, 1, 0.0, 1])
    data["instruments"].append(second)
    path = tmp_path / "two.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SpecError) as e:
        load_spec(path)
    assert [i.path for i in e.value.errors] == ["instruments.1.start.noise"]


def test_an_attempt_carrying_an_old_layout_spec_is_checked_by_its_task_hash():
    from fastrl.data.trajectory import Trajectory, TrajectoryError
    from fastrl.teleop.offline import spec_of_trajectory

    today = load_spec("tracelines")
    old = in_old_layout(yaml.safe_load((SPECS / "tracelines.yaml").read_text()))
    meta = {"task_spec": old, "spec_hash": "0123456789abcdef", "task_hash": task_hash(today)}  # 0.2's spec hash
    attempt = Trajectory(np.array([0.0, 0.05]), np.zeros((2, 5)), meta)
    assert spec_of_trajectory(attempt) == today
    attempt.meta["task_hash"] = "fedcba9876543210"
    with pytest.raises(TrajectoryError, match="task_hash"):
        spec_of_trajectory(attempt)


def test_check_says_a_spec_is_in_the_old_layout_and_where_its_fields_went(tmp_path):
    from typer.testing import CliRunner

    from fastrl.cli import app

    path = tmp_path / "old.yaml"
    path.write_text(yaml.safe_dump(in_old_layout(yaml.safe_load((SPECS / "tracelines.yaml").read_text()))))
    res = CliRunner().invoke(app, ["check", str(path), "tracelines"])
    assert res.exit_code == 0 and res.output.count("ok ") == 2
    assert res.output.count("0.2 layout") == 1 and "episode.resets" in res.output


@pytest.mark.parametrize(
    "field, value",
    [("scope.start.noise", "[5, 5]"), ("scope.start.noise", "lots"), ("task.jitter", "[1, 2, 3]"), ("scope", "[1]")],
)
def test_a_malformed_old_field_is_named_not_a_traceback(tmp_path, field, value):
    data = in_old_layout(yaml.safe_load((SPECS / "triangulation.yaml").read_text()))
    node, *path, last = [data, *field.split(".")]
    for key in path:
        node = node[key]
    node[last] = yaml.safe_load(value)
    spec_file_ = tmp_path / "bad.yaml"
    spec_file_.write_text(yaml.safe_dump(data))
    with pytest.raises(SpecError) as e:
        load_spec(spec_file_)
    assert e.value.errors and all(issue.path.startswith(field.split(".")[0]) for issue in e.value.errors)
