"""The scripted expert completes every subtask of every bundled spec."""

import pytest

import fastrl
from fastrl.agents.expert import run_expert_episode

from ..conftest import spec_file


@pytest.mark.parametrize("mode", ["discrete", "continuous", "rates"])
def test_scripted_expert_completes_all_subtasks(task_name, mode):
    env = fastrl.make(spec_file(task_name), actions={"mode": mode})
    for seed in (0, 1):
        result = run_expert_episode(env, seed=seed)
        assert result["success"], result
        assert result["subtasks"] == result["subtasks_total"] == len(env.unwrapped.task.targets)
