"""A task that ends at the first touch is a spec (fixtures/gentle.yaml): its terminations declare it."""

from pathlib import Path

from fastrl.agents.expert import run_expert_episode
from fastrl.env import FastEnv
from fastrl.spec import SpecError, load_spec, task_hash, world_hash

SPEC = Path(__file__).parents[1] / "fixtures" / "gentle.yaml"
INSERT = 5  # the discrete action that pushes the scope in: from the start pose it runs into the plate
UNTOUCHABLE = ["episode.terminations={subtasks_done: {}}"]  # the same task without the contact termination


def test_the_expert_never_touches_so_both_tasks_run_it_alike():
    gentle, plain = load_spec(SPEC), load_spec(SPEC, UNTOUCHABLE)
    for seed in (0, 1):
        done = run_expert_episode(FastEnv(plain), seed=seed)
        assert run_expert_episode(FastEnv(gentle), seed=seed) == done and done["success"]


def test_the_first_touch_ends_a_gentle_episode_and_only_a_gentle_one():
    for spec, ends in ((load_spec(SPEC, UNTOUCHABLE), False), (load_spec(SPEC), True)):
        env = FastEnv(spec)
        env.reset(seed=0)
        for _ in range(200):
            _, _, terminated, truncated, info = env.step(INSERT)
            if info["contacts"] or terminated or truncated:
                break
        assert info["contacts"] >= 1 and terminated is ends and not truncated and not info["success"]


def test_an_unknown_termination_or_a_bad_parameter_is_refused_at_load_with_its_field():
    for overrides, field in (
        (["episode.terminations={touched: {}}"], "episode.terminations.touched"),
        (["episode.terminations={contact: {force: 2}}"], "episode.terminations.contact.force"),
        (["episode.resets={scope_noise: {pitch_deg: -1}}"], "episode.resets.scope_noise.pitch_deg"),
        (["episode.resets={instrument_noise: {pitch_deg: 1}}"], "episode.resets.instrument_noise"),
    ):
        try:
            load_spec(SPEC, overrides)
        except SpecError as e:
            assert [issue.path for issue in e.errors] == [field]
        else:
            raise AssertionError(f"{overrides} was accepted")


def test_a_declared_termination_makes_another_task_that_the_camera_sees_alike():
    gentle, plain = load_spec(SPEC), load_spec(SPEC, UNTOUCHABLE)
    assert task_hash(gentle) != task_hash(plain) and world_hash(gentle) == world_hash(plain)
