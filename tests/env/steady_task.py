"""A seventh task family, kept in the tests: the dome task that senses how long the scope has been held still."""

import numpy as np

from fastrl.env.dome_task import DomeTask
from fastrl.terms import TERMINATION_TERMS, TaskState
from fastrl.terms.domain import Domain

STILL = 0.002  # m/s: below this tip speed the scope counts as held still


class SteadyState(TaskState):
    """The scope's state and how long its tip has been held still (s)."""

    __slots__ = ("still_for",)

    def __init__(self):
        super().__init__()
        self.still_for = 0.0


class SteadyTask(DomeTask):
    """ImageCentring for a hand that must keep moving: it senses how long the tip has been held still."""

    State = SteadyState

    def initialize_episode(self, rng: np.random.Generator, options: dict) -> None:
        """The dome task's start, the stillness clock at zero."""
        self.state.still_for = 0.0
        super().initialize_episode(rng, options)

    def after_step(self) -> None:
        """The dome task's sensing, then the stillness clock."""
        super().after_step()
        s = self.state
        s.still_for = s.still_for + self.dt if s.tip_speed < STILL else 0.0


@TERMINATION_TERMS.register(domains={"seconds": Domain(0.05, 60.0, unit="a time in s")})
def held_still(s: SteadyState, seconds: float = 1.0) -> bool:
    """The scope's tip has been held still for `seconds`."""
    return s.still_for >= seconds
