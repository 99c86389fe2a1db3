"""What the scope and every instrument share: a shaft through a portal, its reach and its entry-point friction."""

from __future__ import annotations

from pydantic import Field, model_validator

from .base import NonNeg, Pos, Strict, _fail


class Shaft(Strict):
    """A rigid shaft through a portal (the exact fulcrum); subclasses add their `start` pose."""

    portal: str
    shaft_length: float = Field(0.16, gt=0.05, le=0.5)
    diameter: float = Field(0.004, gt=0.001, le=0.02)
    insertion: tuple[NonNeg, Pos] = Field((0.01, 0.15), description="tip depth range past the portal (m)")
    pivot_limit_deg: float = Field(60.0, gt=0, le=85)
    damping: NonNeg = Field(0.05, description="entry-point damping on the portal joints")
    frictionloss: NonNeg = Field(0.002, description="entry-point dry friction on the portal joints")

    @model_validator(mode="after")
    def _ranges(self):
        lo, hi = self.insertion
        if lo >= hi:
            _fail("insertion", f"insertion range must be increasing, got {list(self.insertion)}")
        if hi >= self.shaft_length:
            _fail("insertion", f"insertion {hi} m must be shorter than the shaft ({self.shaft_length} m)")
        if not lo <= self.start.insertion <= hi:
            _fail("start.insertion", f"start insertion {self.start.insertion} m is outside {list(self.insertion)}")
        return self
