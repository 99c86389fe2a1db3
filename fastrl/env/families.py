"""Which Task serves a spec: the family its scene, instruments and loose bodies make it."""

from __future__ import annotations

from ..spec.models import TaskSpec
from .dome_task import DomeTask
from .instrument_task import InstrumentTask
from .loose_task import LooseBodiesTask
from .task import Task
from .tour_task import TourTask


def family_of(spec: TaskSpec) -> type[Task]:
    """The Task class of a spec's family."""
    if spec.task.bodies:
        return LooseBodiesTask
    if spec.instruments:
        return InstrumentTask
    return TourTask if spec.task.kind == "liver_tour" else DomeTask
