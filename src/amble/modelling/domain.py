"""Physical domains of parameters: the interval a value must lie in for the model to mean anything
(a positive mass, a non-negative inertia, a slope a walker can stand on)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Domain:
    """An interval of the real line; each end open (excluded) or closed (included)."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = True
    high_open: bool = True

    def __contains__(self, value: float) -> bool:
        v = float(value)
        if not math.isfinite(v):
            return False
        above = v > self.low if self.low_open else v >= self.low
        below = v < self.high if self.high_open else v <= self.high
        return above and below

    def __str__(self) -> str:
        lo = "−∞" if self.low == -math.inf else f"{self.low:g}"
        hi = "∞" if self.high == math.inf else f"{self.high:g}"
        return f"{'(' if self.low_open else '['}{lo}, {hi}{')' if self.high_open else ']'}"


#: any finite value
REAL = Domain()
#: masses, lengths, gravity: strictly positive
POSITIVE = Domain(0.0)
#: inertias, gains, damping: zero allowed
NONNEGATIVE = Domain(0.0, low_open=False)


def interval(low: float, high: float, closed: bool = False) -> Domain:
    """The interval from ``low`` to ``high``, open unless ``closed``."""
    if not low < high:
        raise ValueError(f"empty interval {low}..{high}")
    return Domain(float(low), float(high), not closed, not closed)


__all__ = ["NONNEGATIVE", "POSITIVE", "REAL", "Domain", "interval"]
