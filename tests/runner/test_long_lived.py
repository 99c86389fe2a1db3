"""The collector skips what lived before a long loop, and takes it back after."""

import gc
import weakref

from fastrl.long_lived import long_lived


class Node:
    """An object that can sit in a reference cycle and be watched."""

    def __init__(self):
        self.me = self


def test_a_cycle_alive_before_the_block_waits_for_its_end_to_be_collected():
    before = Node()
    watch = weakref.ref(before)
    with long_lived():
        made_inside = Node()
        inside = weakref.ref(made_inside)
        del before, made_inside
        gc.collect()
        assert watch() is not None  # frozen: no pass frees it meanwhile
        assert inside() is None  # what the loop makes is collected as usual
    gc.collect()
    assert watch() is None and gc.get_freeze_count() == 0
