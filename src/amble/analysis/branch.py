"""A continued branch and what lies on it: its gaits (:class:`BranchPoint`), the folds, flips
and torus points located between them (:class:`BifurcationPoint`) and the branch itself
(:class:`Branch`).

Plain results, apart from :mod:`amble.analysis.continuation` (which traces a branch) and
:mod:`amble.analysis.bifurcation_location` (which locates a bifurcation on it): sweeps read
and make them from their rows without continuing anything.

Units: states in the model's units (rad, rad/s), the parameter in its own, times in s.

"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .multipliers import resonance, torus_pair

__all__ = ["BifurcationPoint", "Branch", "BranchPoint"]


@dataclass
class BranchPoint:
    """One converged gait of a branch: parameter ``value``, post-impact ``state`` (full state),
    the ``orbit`` (k post-impact states, ``state`` first) and ``step_times`` (k, s), the
    nontrivial ``multipliers``, the ``residual`` ``|P(x) − x|∞`` and the arclength ``s``."""

    value: float
    state: np.ndarray
    orbit: np.ndarray
    step_times: list[float]
    multipliers: np.ndarray
    residual: float
    s: float = 0.0

    @property
    def stable(self) -> bool:
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    @property
    def max_modulus(self) -> float:
        return float(np.max(np.abs(self.multipliers)))


@dataclass
class BifurcationPoint:
    """A fold (a real multiplier through +1: a turning point of the branch, or a branch point
    such as a period-1 orbit continued as a 2-step fixed point at its flip), a flip (one
    through −1) or a torus (Neimark–Sacker) point (a complex pair through the unit circle)
    located on a branch: ``kind`` ``"fold"``, ``"flip"`` or ``"torus"``, the gait there
    (``point``) and the test function's value."""

    kind: str
    point: BranchPoint
    test: float
    #: False when the location failed (e.g. the corrector at a branch point, where two branches
    #: cross): ``point`` is then the bracketing branch point with the smaller |test|
    located: bool = True
    #: the gait's stability on either side, in the order the branch was traced (parameter
    #: increasing for a sweep's grid): ``"stable→unstable"``, ``"unstable→stable"`` or
    #: ``"unstable→unstable"`` (another multiplier outside the unit circle on both sides)
    direction: str = ""

    @property
    def value(self) -> float:
        return self.point.value

    @property
    def angle(self) -> float | None:
        """A torus point's θ = |arg μ| (rad, in [0, π]) of the pair on the unit circle; ``None``
        for a fold or a flip."""
        pair = torus_pair(self.point.multipliers) if self.kind == "torus" else None
        return pair[1] if pair else None

    @property
    def rotation(self) -> float | None:
        """A torus point's rotation number θ / 2π (turns per step of the map) of the invariant
        circle born there; ``None`` for a fold or a flip."""
        a = self.angle
        return None if a is None else a / (2 * math.pi)

    @property
    def resonance(self) -> str | None:
        """A torus point at a strong resonance (θ = 0, π, 2π/3, π/2 within
        :data:`~amble.analysis.multipliers.RESONANCE_TOL`): ``"1:1"``, ``"1:2"``, ``"1:3"`` or
        ``"1:4"``; otherwise ``None``."""
        a = self.angle
        return None if a is None else resonance(a)

    def to_json(self) -> dict[str, Any]:
        """The point as plain data: kind, parameter value, period, multipliers ([re, im] pairs),
        located, direction, and for a torus point its angle, rotation number and resonance."""
        out: dict[str, Any] = {"kind": self.kind, "value": self.value, "period": len(self.point.orbit),
                               "multipliers": [[float(m.real), float(m.imag)] for m in self.point.multipliers],
                               "located": self.located, "direction": self.direction}
        if self.kind == "torus":
            out.update(angle=self.angle, rotation=self.rotation, resonance=self.resonance)
        return out


@dataclass
class Branch:
    """A continued branch of period-``period`` gaits of ``system`` in parameter ``param``: its
    points in the order traced, the bifurcations located on it, and why it ended (``end``)."""

    system: str
    param: str
    period: int
    state_names: list[str]
    points: list[BranchPoint] = field(default_factory=list)
    bifurcations: list[BifurcationPoint] = field(default_factory=list)
    end: str = ""

    def values(self) -> np.ndarray:
        return np.array([p.value for p in self.points])

    def flips(self) -> list[BifurcationPoint]:
        return [b for b in self.bifurcations if b.kind == "flip"]

    def folds(self) -> list[BifurcationPoint]:
        return [b for b in self.bifurcations if b.kind == "fold"]

    def tori(self) -> list[BifurcationPoint]:
        """The torus (Neimark–Sacker) points: a complex pair of multipliers through |μ| = 1."""
        return [b for b in self.bifurcations if b.kind == "torus"]
