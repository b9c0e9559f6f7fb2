"""A period-doubling cascade followed branch by branch, with its bifurcation points and
Feigenbaum's ratios.

Starting from the period-1 branch, each branch is continued (:func:`continue_branch`,
pseudo-arclength with located flips) until its first flip, where the period-doubled branch is
switched onto (:func:`switch_at_flip`, along the flip's eigenvector) and continued in turn. Near
the accumulation point the intervals between successive flips shrink geometrically, by
Feigenbaum's δ ≈ 4.6692 for a generic one-parameter family of maps with a quadratic extremum: so
each new branch is continued over a range and with steps scaled from the last interval,

    range_k = [λ_k, λ_k + (λ_k − λ_{k−1}) / 2],     max_delta_k = (λ_k − λ_{k−1}) / 40,

(about 2.3 times the next interval expected, in some 20 steps) rather than with the steps of the
first branch, which would step over the next flip. A switch that does not converge is retried
with a ten times smaller amplitude (the period-doubled orbits split as the square root of the
distance from the flip, and the deeper branches lie in ever smaller intervals).

The ratios of successive intervals, ``δ_n = (λ_{n+1} − λ_n) / (λ_{n+2} − λ_{n+1})``, tend to δ.

Units: the parameter in its own units.

Reference: M. J. Feigenbaum, "Quantitative universality for a class of nonlinear
transformations", J. Stat. Phys. 19(1):25–52, 1978.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import AmbleError, StateError
from .branch import BifurcationPoint, Branch
from .continuation import continue_branch, switch_at_flip
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: Feigenbaum's constant δ (Feigenbaum 1978; 4.669201609… to the digits given there).
FEIGENBAUM_DELTA = 4.669201609102990


@dataclass
class Cascade:
    """The branches of a cascade (periods 1, 2, 4, …), the flips found (``flips[n]``: the first
    flip of ``branches[n]``, where the period ``2^n`` gait period-doubles) and why it ended.
    Torus (Neimark–Sacker) points the branches cross are on each branch (:meth:`Branch.tori`)."""

    param: str
    branches: list[Branch] = field(default_factory=list)
    flips: list[BifurcationPoint] = field(default_factory=list)
    end: str = ""

    @property
    def values(self) -> np.ndarray:
        """The parameter at each flip, in order."""
        return np.array([f.value for f in self.flips])

    @property
    def intervals(self) -> np.ndarray:
        """``λ_{n+1} − λ_n``: the parameter range of each period-``2^(n+1)`` gait's stability."""
        return np.diff(self.values)

    @property
    def ratios(self) -> np.ndarray:
        """Feigenbaum's ratios ``δ_n``, of each interval to the next."""
        d = self.intervals
        return d[:-1] / d[1:]

    def to_json(self) -> dict[str, Any]:
        return {"param": self.param, "periods": [b.period for b in self.branches],
                "flips": [{"period": b.period, "value": f.value, "located": f.located}
                          for b, f in zip(self.branches, self.flips)],
                "tori": [{**t.to_json(), "branch": n} for n, b in enumerate(self.branches) for t in b.tori()],
                "intervals": self.intervals.tolist(), "ratios": self.ratios.tolist(), "end": self.end}


def period_doublings(system: HybridSystem, param: str, start: float, stop: float, *, levels: int = 4,
                     params: Mapping[str, float] | None = None, guess: Sequence[float] | None = None,
                     max_delta: float | None = None, amplitude: float = 1e-3, rtol: float = FIXED_POINT_TOL,
                     atol: float = FIXED_POINT_TOL, tol: float = RESIDUAL_TOL) -> Cascade:
    """Follow the period-doubling cascade of the period-1 gait in ``param`` from ``start`` towards
    ``stop``: up to ``levels`` branches (periods 1, 2, …, 2^(levels−1)) and their first flips.

    ``max_delta``: the period-1 branch's largest parameter step (default |stop − start| / 50);
    the deeper branches scale theirs from the last interval (module doc). ``amplitude``: the
    first switch's offset along the flip eigenvector (state units), divided by 10 on each retry
    (at most twice). ``Cascade.end`` says why the cascade ended.
    """
    if levels < 1:
        raise StateError(f"levels must be at least 1, got {levels}")
    kw = dict(params=params, rtol=rtol, atol=atol, tol=tol)
    out = Cascade(param=param)
    br = continue_branch(system, param, start, stop, guess=guess, max_delta=max_delta, **kw)
    out.branches.append(br)
    sign = 1.0 if stop > start else -1.0
    while True:
        flips = [f for f in br.flips() if f.located]
        if not flips:
            out.end = f"no flip on the period-{br.period} branch ({br.end})"
            return out
        out.flips.append(flips[0])
        if len(out.branches) == levels:
            out.end = f"{levels} levels"
            return out
        lam = flips[0].value
        span = abs(lam - out.flips[-2].value) if len(out.flips) > 1 else abs(stop - start)
        end = stop if len(out.flips) == 1 else lam + sign * min(span / 2, abs(stop - lam))
        step = max_delta if len(out.flips) == 1 else span / 40
        error: AmbleError | None = None
        for a in (amplitude, amplitude / 10, amplitude / 100):
            try:
                br = switch_at_flip(system, flips[0], param, end, period=br.period, amplitude=a, max_delta=step, **kw)
                break
            except AmbleError as e:
                error = e
        else:
            out.end = f"no period-{2 * br.period} branch at {param} = {lam:.12g} ({error})"
            return out
        out.branches.append(br)


__all__ = ["FEIGENBAUM_DELTA", "Cascade", "period_doublings"]
