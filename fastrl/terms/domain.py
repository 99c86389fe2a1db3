"""The domain of a term parameter (bounds, whole or not) and the one-line problem a value outside it gives."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Domain:
    """Allowed values of one numeric parameter: finite, in [lo, hi], whole if `integer`; `unit` says what it is."""

    lo: float | None = None
    hi: float | None = None
    integer: bool = False
    unit: str = ""

    def describe(self) -> str:
        """The domain in words, e.g. 'a number from 1e-06 (a length in m)'."""
        text = "a whole number" if self.integer else "a number"
        if self.lo is not None and self.hi is not None:
            text += f" from {self.lo:g} to {self.hi:g}"
        elif self.lo is not None:
            text += f" of at least {self.lo:g}"
        elif self.hi is not None:
            text += f" of at most {self.hi:g}"
        return f"{text} ({self.unit})" if self.unit else text

    def problem(self, value: Any) -> str | None:
        """Why `value` is outside the domain (one line), or None if it is inside."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return f"must be {self.describe()}, got {value!r}"
        if isinstance(value, float) and not math.isfinite(value):
            return f"must be a finite number, got {value!r}"
        outside = (
            (self.integer and isinstance(value, float) and not value.is_integer())
            or (self.lo is not None and value < self.lo)
            or (self.hi is not None and value > self.hi)
        )
        return f"must be {self.describe()}, got {value!r}" if outside else None


TINY = 1e-6  # the smallest margin, speed or scale: near zero a feature divides by zero or overflows to inf
LENGTH = Domain(TINY, 1.0, unit="a length in m, above zero")
ANGLE = Domain(TINY, 180.0, unit="an angle in degrees, above zero")
SPEED = Domain(TINY, 100.0, unit="a speed in m/s, above zero")
ACCELERATION = Domain(TINY, 1e4, unit="an acceleration in m/s^2, above zero")
DISTANCE = Domain(0.0, 1.0, unit="a distance in m")
FRACTION = Domain(0.0, 1.0, unit="a fraction")
COUNT = Domain(1, None, integer=True, unit="a count")
