"""Each bundled spec runs on its family's Task, over that family's own state record."""

import pytest

from fastrl.env.dome_task import DomeTask
from fastrl.env.families import family_of
from fastrl.env.instrument_task import InstrumentTask
from fastrl.env.loose_task import LooseBodiesTask
from fastrl.env.tour_task import TourTask
from fastrl.spec import load_spec
from fastrl.terms import InstrumentState, TaskState

from ..conftest import spec_file

FAMILIES = {
    "imagecentring": DomeTask,
    "periscoping": DomeTask,
    "tracelines": DomeTask,
    "tracelines_pixels": DomeTask,
    "liver_tour": TourTask,
    "triangulation": InstrumentTask,
    "loose_bodies": LooseBodiesTask,
}


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_a_bundled_spec_gets_its_family(name):
    family = family_of(load_spec(spec_file(name)))
    assert family is FAMILIES[name]
    assert family.State is (InstrumentState if issubclass(family, InstrumentTask) else TaskState)


def test_only_the_instrument_families_keep_instrument_state():
    assert not hasattr(TaskState(), "instrument_pos") and hasattr(InstrumentState(), "instrument_pos")
    scope = load_spec(spec_file("imagecentring"))
    assert family_of(scope) is DomeTask
    with_probe = load_spec(spec_file("triangulation"), ["task.kind=image_centring"])
    assert family_of(with_probe) is InstrumentTask  # instruments, whatever the kind, make an instrument task
