"""The instrument tasks (Triangulation): the scope views each target while an instrument's tip touches it."""

from __future__ import annotations

import mujoco
import numpy as np

from ..terms import EpisodeStart
from ..terms.state import InstrumentState
from .dome_task import DomeTask
from .instrument_actions import InstrumentActions
from .instrument_sensing import InstrumentSensor, instrument_start, place_instrument_joints, with_jaws


class InstrumentTask(DomeTask):
    """The dome task with instruments in portals of their own: their actions, sensing, and touch in the cue."""

    State = InstrumentState
    reads_past = False  # green needs an instrument on the target: a replay reads each avatar's own hold

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.instrument_sensor = InstrumentSensor(self.compiled)

    def make_actions(self):
        """The scope's actions, then every instrument coordinate's."""
        cfg = self.compiled.spec.actions
        return InstrumentActions(super().make_actions(), cfg, self.compiled.instruments, self.dt)

    def episode_start(self, options: dict) -> EpisodeStart:
        """The scope's start, and the instruments' as the spec gives them (None where the options do)."""
        start = super().episode_start(options)
        start.instruments = None if options.get("instruments") is not None else instrument_start(self.compiled)
        return start

    def place_start(self, start: EpisodeStart, options: dict) -> None:
        """The scope, then the instruments at their start (the options' coordinates, where they give them)."""
        super().place_start(start, options)
        given = start.instruments is None
        q = np.asarray(options["instruments"], float) if given else with_jaws(self.compiled, start.instruments)
        self.place_instruments(q)

    def sense(self, first: bool) -> None:
        """Read the scope, then the instruments."""
        self.sensor.read(self.state, self.model, self.data, first=first)
        self.instrument_sensor.read(self.state, self.model, self.data, first=first)

    def retarget(self) -> None:
        """The scope's and the instruments' target-dependent quantities."""
        self.sensor.errors(self.state, self.model, self.data)
        self.instrument_sensor.errors(self.state, self.model, self.data)

    def cue(self) -> dict:
        """The cue, with the working instrument touching the target."""
        cue = super().cue()
        cue["touching"] = self.state.instrument_touching
        return cue

    def place_instruments(self, q: np.ndarray, positions_only: bool = False) -> None:
        """Set the instruments' coordinates at rest, servos holding there, and recompute positions."""
        n = sum(len(t.qadr) for t in self.compiled.instruments)
        if q.shape != (n,) or not np.isfinite(q).all():
            raise ValueError(f"instrument coordinates must be {n} finite numbers, got {q!r}")
        self.target = self.target[:5] + place_instrument_joints(self.compiled, self.data, q).tolist()
        self.positions_only = positions_only
        (mujoco.mj_fwdPosition if positions_only else mujoco.mj_forward)(self.model, self.data)

    def place_recorded(self, portal, instruments=None, bodies=None) -> None:
        """Replay: the scope, then the instruments if recorded."""
        super().place_recorded(portal)
        if instruments is not None:
            self.place_instruments(np.asarray(instruments, float), positions_only=True)
