"""Where the period-1 gait period-doubles, read from any sweep's result: one detector.

A period doubling (a flip) is where a real Floquet multiplier of the period-1 gait crosses −1.
It is *located* in one place, :func:`amble.analysis.bifurcation_location.locate_flip`: the zero of
``ψ_flip = det(A + I)`` between two gaits of the branch, by the secant method with bisection,
each iterate corrected onto the branch. Continuation locates the flips it passes with it while it
traces a branch; :func:`period_doubling` finds the bracketing pair in the rows of a fixed-point
branch and locates the flip between them with it. A bifurcation diagram holds no multipliers:
from it, the first value whose attractor repeats with a period of 2 or more is what is known.
Every fold, flip and torus point a branch crosses, by one mechanism, is
:func:`~amble.analysis.branch_bifurcations.bifurcations`.

Units: the swept parameter in its own units.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING

from ..errors import StateError
from .bifurcation_location import locate_flip
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .store import SweepResult, state_from_row

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


def _lowest_real(row: Mapping[str, str]) -> float:
    """The lowest real multiplier of a stored row (``inf`` when none is real)."""
    real = [re for re, im in json.loads(row["multipliers"]) if abs(im) < 1e-9 * max(1.0, abs(re))]
    return min(real) if real else math.inf


def _branch(result: SweepResult, system: HybridSystem | None, params: Mapping[str, float] | None) -> float | None:
    """A fixed-point branch: the first pair of neighbouring converged points whose lowest real
    multiplier lies on either side of −1, then the flip located between them (with ``system``),
    or the linear interpolation of that multiplier between them (without)."""
    p = result.params[0]
    prev = None
    for r in result.rows:
        if r["status"] != "ok":
            prev = None
            continue
        cur = (r, float(r[p]), _lowest_real(r))
        if prev is not None and math.isfinite(prev[2]) and math.isfinite(cur[2]) and (prev[2] + 1) * (cur[2] + 1) < 0:
            (ra, x0, y0), (rb, x1, y1) = prev, cur
            if system is None:
                return x0 + (-1 - y0) * (x1 - x0) / (y1 - y0)
            a, b = (state_from_row(row, result.state_names) for row in (ra, rb))
            if a is None or b is None:
                raise StateError("the result's rows lack their states: the flip cannot be located")
            flip = locate_flip(system, p, (a, x0), (b, x1), params=params, rtol=FIXED_POINT_TOL,
                               atol=FIXED_POINT_TOL, tol=RESIDUAL_TOL)
            if flip is not None:  # None: ψ_flip has the same sign at both (a pair of crossings)
                return flip.value
        prev = cur
    return None


def _continuation(result: SweepResult, system: HybridSystem | None, params: Mapping[str, float] | None
                  ) -> float | None:
    """A continuation: its first flip on the period-1 branch, located as the branch was traced."""
    p = result.params[0]
    flips = [r for r in result.rows if r["row"] == "flip" and r["branch"] == "0" and r["status"] == "ok"]
    return float(min(flips, key=lambda r: int(r["i"]))[p]) if flips else None


def _iterates(result: SweepResult, system: HybridSystem | None, params: Mapping[str, float] | None
              ) -> float | None:
    """A bifurcation diagram: the first swept value whose post-transient iterates repeat with a
    period ≥ 2 (period 0 is skipped: near the flip the transient decays too slowly to show one)."""
    p = result.params[0]
    for r in result.rows:
        if r["status"] == "ok" and r["period"] not in ("", "0", "1"):
            return float(r[p])
    return None


#: result kind → how its rows tell where the period-1 gait period-doubles
_READERS: dict[str, Callable[[SweepResult, HybridSystem | None, Mapping[str, float] | None], float | None]] = {
    "fixed-point": _branch, "continuation": _continuation, "bifurcation": _iterates}


def period_doubling(result: SweepResult, system: HybridSystem | None = None, *,
                    params: Mapping[str, float] | None = None) -> float | None:
    """The first value of the swept parameter where the period-1 gait period-doubles, or ``None``.

    - a fixed-point branch (``amble.sweep(system, "fixed-point", {param: values})``): between the
      first two neighbouring converged points whose lowest real multiplier lies on either side of
      −1, the flip is located on the branch (:func:`~amble.analysis.bifurcation_location.locate_flip`:
      the multiplier there is −1 to about 1e-8) when the ``system`` is given, with ``params`` the
      sweep's other parameters; without it, the multiplier is interpolated linearly between the
      two points (an estimate, off by the grid's curvature);
    - a continuation: its first flip on the period-1 branch (located the same way as it was traced);
    - a bifurcation diagram: the first value whose attractor repeats with a period ≥ 2 (no
      multipliers are stored: the grid value where the diagram shows the doubling).
    """
    kind = getattr(result, "kind", type(result).__name__)  # a basin's result has no kind: it is refused too
    reader = _READERS.get(kind)
    if reader is None:
        raise StateError(f"period_doubling reads a result of kind {', '.join(_READERS)}, not {kind!r}")
    return reader(result, system, params)


__all__ = ["period_doubling"]
