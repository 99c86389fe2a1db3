"""The task states that reward features and observation terms read: plain floats and tuples, no MuJoCo."""

from __future__ import annotations


class TaskState:
    """What the scope's terms read at one control step (every family has the scope); its Task fills it in place."""

    __slots__ = (
        "time",
        "time_limit",
        "dt",
        "gamma",
        "tip_pos",
        "tip_quat",
        "tip_vel",
        "tip_quat_rate",
        "tip_speed",
        "tip_accel",
        "cam_pos",
        "cam_fwd",
        "cam_up",
        "cam_right",
        "fov",
        "portal",
        "portal_vel",
        "portal_lo",
        "portal_hi",
        "target_pos",
        "target_quat",
        "target_fwd",
        "target_up",
        "centring",
        "horizon",
        "distance",
        "dist_lo",
        "dist_hi",
        "tol_centring",
        "tol_horizon",
        "dwell_time",
        "green",
        "dwell",
        "prev_dwell",
        "dwell_best",
        "dwell_gain",
        "completed",
        "subtask",
        "subtasks_total",
        "subtasks_done",
        "contacts",
        "line_deviation",
        "ray_fraction",
        "potential",
        "prev_potential",
        "goals",
        "task_ok",
    )

    def __init__(self):
        z3 = (0.0, 0.0, 0.0)
        self.time, self.time_limit, self.dt, self.gamma = 0.0, 1.0, 0.05, 0.99
        self.tip_pos = self.tip_vel = self.tip_accel = self.cam_pos = z3
        self.tip_quat, self.tip_quat_rate = (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)
        self.tip_speed = 0.0
        self.cam_fwd, self.cam_up, self.cam_right = (0.0, 0.0, -1.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)
        self.fov = 1.0
        self.portal = self.portal_vel = (0.0,) * 5
        self.portal_lo, self.portal_hi = (-1.0,) * 5, (1.0,) * 5
        self.target_pos, self.target_quat = z3, (1.0, 0.0, 0.0, 0.0)
        self.target_fwd, self.target_up = (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)
        self.centring = self.horizon = self.distance = 0.0
        self.dist_lo, self.dist_hi = 0.02, 0.05
        self.tol_centring, self.tol_horizon, self.dwell_time = 0.14, 0.26, 0.5
        self.green = self.completed = False
        self.dwell = self.prev_dwell = self.dwell_best = self.dwell_gain = 0.0
        self.subtask, self.subtasks_total, self.subtasks_done = 0, 1, 0
        self.contacts = 0
        self.line_deviation = self.ray_fraction = 0.0
        self.potential = self.prev_potential = 0.0
        self.goals = z3
        self.task_ok = True  # the family's own condition for green (an instrument on the target): none here

    @property
    def distance_error(self) -> float:
        """Signed distance outside the allowed range (0 inside, <0 too close, >0 too far)."""
        if self.distance < self.dist_lo:
            return self.distance - self.dist_lo
        if self.distance > self.dist_hi:
            return self.distance - self.dist_hi
        return 0.0

    def copy_from(self, other: TaskState) -> None:
        """Take every field of another state of the same kind."""
        for name in _fields(type(self)):
            setattr(self, name, getattr(other, name))


class InstrumentState(TaskState):
    """The scope's state and the instruments': what the instrument families' terms read."""

    __slots__ = (
        "instrument_pos",
        "instrument_quat",
        "instrument_vel",
        "instrument_portal",
        "instrument_to_target",
        "instrument_distance",
        "instrument_touching",
        "instrument_contacts",
        "instrument_in_view",
        "instrument_potential",
        "prev_instrument_potential",
        "instrument_holding",
        "prev_instrument_holding",
        "instruments_pos",
        "instruments_quat",
        "instruments_vel",
        "instruments_to_target",
        "instruments_touching",
        "instruments_in_view",
        "instruments_portal",
    )

    def __init__(self):
        super().__init__()
        z3 = (0.0, 0.0, 0.0)
        self.instrument_pos = self.instrument_vel = self.instrument_to_target = z3
        self.instrument_quat, self.instrument_portal = (1.0, 0.0, 0.0, 0.0), (0.0,) * 4
        self.instrument_distance, self.instrument_contacts = 0.0, 0
        self.instrument_touching = self.instrument_in_view = False
        self.instrument_potential = self.prev_instrument_potential = 0.0
        self.instrument_holding = self.prev_instrument_holding = False
        # every instrument, spec order, flattened (the working one first): what the per-instrument terms read
        self.instruments_pos = self.instruments_vel = self.instruments_to_target = self.instruments_quat = (
            self.instruments_portal
        ) = ()
        self.instruments_touching = self.instruments_in_view = ()


def _fields(cls: type) -> tuple[str, ...]:
    """Every slot of a state class and its bases."""
    return tuple(n for c in reversed(cls.__mro__) for n in c.__dict__.get("__slots__", ()))
