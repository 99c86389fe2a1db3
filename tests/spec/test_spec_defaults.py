"""Defaults that depend on the algorithm are resolved once, when the spec is loaded, and recorded in spec.yaml."""

import pytest
import yaml
from pydantic import ValidationError

from fastrl.runner.runs.rundir import write_spec
from fastrl.spec import SpecError, TaskSpec, load_spec, spec_hash, task_hash

from ..conftest import spec_file

DISC = ("irl", "discriminator")


def value(data: dict, path: tuple) -> object:
    for name in path:
        data = data[name]
    return data


@pytest.mark.parametrize(
    ("sets", "expected"),
    [
        (["irl.algorithm=gail"], {"reward": True, "ignore": ["elapsed"], "policy_term": True, "scale_reward": False}),
        (
            ["irl.algorithm=airl", "train.algo=SAC", "actions.mode=rates"],
            {"reward": False, "ignore": [], "policy_term": False, "scale_reward": True},
        ),
    ],
)
def test_the_runs_spec_yaml_records_the_resolved_defaults(tmp_path, sets, expected):
    spec = load_spec(spec_file("tracelines"), sets)
    write_spec(tmp_path, spec, "<mujoco/>")
    saved = yaml.safe_load((tmp_path / "spec.yaml").read_text())
    assert saved["train"]["normalize"]["reward"] is expected["reward"]
    for name in ("ignore", "policy_term", "scale_reward"):
        assert value(saved, (*DISC, name)) == expected[name]
    assert load_spec(tmp_path / "spec.yaml") == spec


def test_an_old_spec_yaml_with_nulls_loads_resolved_the_same_way_and_keeps_its_hash():
    spec = load_spec(spec_file("imagecentring"), ["irl.algorithm=gail"])
    old = spec.model_dump(mode="json")
    old["train"]["normalize"]["reward"] = None
    for name in ("ignore", "policy_term", "scale_reward"):
        old["irl"]["discriminator"][name] = None
    again = TaskSpec.model_validate(old)
    assert again == spec and spec_hash(again) == spec_hash(spec)
    assert spec_hash(load_spec(spec_file("imagecentring"), ["irl.algorithm=gail", "irl.discriminator.ignore=[]"])) != (
        spec_hash(spec)
    )


def test_without_a_discriminator_its_defaults_wait_for_the_algorithm(tmp_path):
    spec = load_spec(spec_file("imagecentring"))  # a study's spec.yaml is run again as GAIL and as AIRL
    assert spec.irl.discriminator.ignore is None and spec.train.normalize.reward is True
    write_spec(tmp_path, spec, "<mujoco/>")
    gail = load_spec(tmp_path / "spec.yaml", ["irl.algorithm=gail"])
    assert gail.irl.discriminator.ignore == ["elapsed"] and gail.irl.discriminator.scale_reward is False


def test_gail_ignores_the_clock_only_where_it_is_observed():
    unset = ["irl.algorithm=gail", "irl.discriminator.ignore=null"]
    without = load_spec(spec_file("liver_tour"), [*unset, "observation.extra=[]"])
    with_clock = load_spec(spec_file("liver_tour"), [*unset, "observation.extra=[elapsed]"])
    assert without.irl.discriminator.ignore == [] and with_clock.irl.discriminator.ignore == ["elapsed"]


def test_a_removed_option_is_an_unknown_field_with_its_file_and_line(tmp_path):
    spec = load_spec(spec_file("imagecentring"), ["irl.algorithm=airl"])
    old = spec.model_dump(mode="json")
    old["irl"]["discriminator"]["entropy"] = True  # removed before 0.2: the AIRL reward always keeps -log pi
    (tmp_path / "spec.yaml").write_text(yaml.safe_dump(old))
    with pytest.raises(SpecError) as err:
        load_spec(tmp_path / "spec.yaml")
    assert [(e.path, e.line is not None) for e in err.value.errors] == [("irl.discriminator.entropy", True)]


def test_resolving_the_defaults_leaves_the_spec_it_was_given_alone():
    spec = load_spec(spec_file("imagecentring"))
    data = spec.model_dump(mode="json")
    data["irl"]["algorithm"] = "gail"
    gail = TaskSpec.model_validate(data)
    assert gail.irl.discriminator.ignore == ["elapsed"] and spec.irl.discriminator.ignore is None
    with pytest.raises(ValidationError):
        gail.irl = spec.irl  # frozen


def test_a_generator_option_changes_the_hash():
    spec = load_spec(spec_file("periscoping"))
    late = load_spec(spec_file("periscoping"), ["irl.generator.late_starts=0.5"])
    assert spec_hash(late) != spec_hash(spec) and task_hash(late) == task_hash(spec)


def test_later_subtasks_are_forward_rl_alone_on_a_dome_task_and_change_no_task_hash():
    spec = load_spec(spec_file("imagecentring"))
    assert spec.train.later_subtasks == 0.5 and spec.training_later_subtasks == 0.5
    assert load_spec(spec_file("imagecentring"), ["irl.algorithm=airl"]).training_later_subtasks == 0.0
    assert load_spec(spec_file("imagecentring"), ["irl.algorithm=bc"]).training_later_subtasks == 0.0
    assert load_spec(spec_file("tracelines")).training_later_subtasks == 0.0
    none = load_spec(spec_file("imagecentring"), ["train.later_subtasks=0"])
    assert task_hash(none) == task_hash(spec) and spec_hash(none) != spec_hash(spec)
    for name in ("liver_tour", "triangulation"):
        with pytest.raises(SpecError, match="later_subtasks") as exc:
            load_spec(spec_file(name), ["train.later_subtasks=0.5"])
        assert "ordered avatars" in str(exc.value)
