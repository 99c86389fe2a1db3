"""How many of `fastrl assess --seeds N`'s seeds learn at once: on spare cores, before this process renders."""

import os

from fastrl.runner import seeds_at_once
from fastrl.runner.seeds_at_once import at_once


def test_seeds_learn_at_once_up_to_two_per_core_and_never_after_rendering(monkeypatch):
    monkeypatch.setattr(seeds_at_once, "rendered_here", lambda: False)  # as in a fresh command's process
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    assert at_once(3) == 1  # one core: one after another
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    assert [at_once(n) for n in (1, 3, 10)] == [1, 3, 4]
    monkeypatch.setattr(seeds_at_once, "rendered_here", lambda: True)  # a forked child's EGL would deadlock
    assert at_once(3) == 1
