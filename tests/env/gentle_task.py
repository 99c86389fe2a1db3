"""A seventh task family, kept in the tests: the dome task where touching the shell or the plate ends the episode."""

from fastrl.env.dome_task import DomeTask


class GentleTask(DomeTask):
    """ImageCentring for a gentle hand: the episode ends (unsuccessful) the moment the scope's tip touches anything."""

    def get_termination(self) -> bool:
        """The dome task's end (every avatar done), or the first contact."""
        return super().get_termination() or self.state.contacts > 0
