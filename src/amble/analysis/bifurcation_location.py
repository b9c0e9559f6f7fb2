"""The location of a fold, flip or torus point between two gaits of one branch: the one
location continuation, sweeps and the period-doubling detector use.

**Test functions.** With ``A = Uᵀ (∂P/∂x) U`` (``U`` an orthonormal basis of Σ's tangent space,
:meth:`Section.tangent`; ``A``'s eigenvalues are the multipliers, whatever the basis)

    ψ_fold = det(A − I),     ψ_flip = det(A + I),     ψ_torus = det(A ⊙ A − I)

change sign where a real multiplier crosses +1 (a fold) or −1 (a period doubling); a complex
pair never changes the first two's sign (|μ ∓ 1|² > 0), but crosses the unit circle where ψ_torus
(``A ⊙ A`` the bialternate product, eigenvalues μᵢμⱼ, :mod:`amble.analysis.multipliers`) changes
sign: a Neimark–Sacker (torus) bifurcation, reported with the pair's angle θ = arg μ there. A zero
of ψ_torus where the pair with μᵢμⱼ = 1 is real (a neutral saddle) is no bifurcation and is
dropped. A sign change between two branch points is located
by the secant method (Newton with the derivative from the last two iterates: dψ/dσ needs second
derivatives of the map) on ``ψ(σ)``, where ``σ ∈ [0, 1]`` runs along the chord between the two
points and each ``σ`` is corrected onto the branch in the hyperplane normal to the chord. Secant
steps that would leave the bracket are replaced by bisection; the iteration ends when λ moves
less than :data:`LOCATE_TOL`.

Apart from :mod:`amble.analysis.continuation`: a sweep locates a bifurcation between two of
its rows (:func:`locate_bifurcation`, :func:`locate_flip`) without tracing a branch.

Units: states in the model's units (rad, rad/s), the parameter in its own, times in s.

"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..errors import AmbleError, StateError
from .branch import BifurcationPoint, BranchPoint
from .branch_corrector import _correct, _Problem
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .multipliers import KINDS, crossing_functions, torus_pair

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: A located bifurcation's parameter is known to this (parameter units) or better.
LOCATE_TOL = 1e-12


def _tests(A: np.ndarray) -> tuple[float, float, float]:
    """(ψ_fold, ψ_flip, ψ_torus) = (det(A − I), det(A + I), det(A ⊙ A − I)), in ``KINDS`` order."""
    return crossing_functions(A)


def _locate(prob: _Problem, ua: np.ndarray, ub: np.ndarray, kind: str, tol: float) -> BifurcationPoint:
    """The zero of ψ_kind between two branch points: secant iterations in σ (bisection when a
    secant step leaves the bracket), each σ corrected onto the branch normal to the chord."""
    d = ub - ua
    nd = d / np.linalg.norm(d)
    which = KINDS.index(kind)

    def at(sig: float) -> tuple[float, np.ndarray, np.ndarray, float]:
        u0 = ua + sig * d
        u, J, res, _ = _correct(prob, u0, nd, tol)
        return _tests(prob.reduced(u, J))[which], u, J, res

    a, b = 0.0, 1.0
    fa, *_ = at(a)
    fb, *_ = at(b)
    x0, f0, x1, f1 = a, fa, b, fb
    best = None
    for _ in range(60):
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0) if f1 != f0 else 0.5 * (a + b)
        if not a < x2 < b:
            x2 = 0.5 * (a + b)
        f2, u, J, res = at(x2)
        best = (f2, u, J, res)
        if f2 * fa < 0:
            b, fb = x2, f2
        else:
            a, fa = x2, f2
        x0, f0, x1, f1 = x1, f1, x2, f2
        if abs(x1 - x0) * abs(d[-1]) < LOCATE_TOL or f2 == 0.0 or (b - a) * abs(d[-1]) < LOCATE_TOL:
            break
    assert best is not None
    f2, u, J, res = best
    return BifurcationPoint(kind=kind, point=prob.point(u, J, res, 0.0), test=f2)


def _bracketed(prob: _Problem, ua: np.ndarray, ub: np.ndarray, kind: str, tol: float,
               near_a: tuple[BranchPoint, float], near_b: tuple[BranchPoint, float]) -> BifurcationPoint | None:
    """The bifurcation between two branch points whose test functions differ in sign, located
    (:func:`_locate`); when the location fails, the bracketing point with the smaller |test|
    (``located=False``). ``near_a``, ``near_b``: each end's point and test value. ``None`` for
    a zero of ψ_torus whose pair is real and distinct (a neutral saddle: no bifurcation)."""
    try:
        bp = _locate(prob, ua, ub, kind, tol)
    except AmbleError:  # ConvergenceError, SimulationError: e.g. the corrector at a branch point
        pt, test = near_a if abs(near_a[1]) < abs(near_b[1]) else near_b
        bp = BifurcationPoint(kind, pt, test, located=False)
    if kind == "torus" and torus_pair(bp.point.multipliers) is None:
        return None
    bp.direction = "→".join("stable" if p.stable else "unstable" for p in (near_a[0], near_b[0]))
    return bp


def locate_bifurcation(system: HybridSystem, param: str, a: tuple[Sequence[float], float],
                       b: tuple[Sequence[float], float], kind: str, *, params: Mapping[str, float] | None = None,
                       period: int = 1, rtol: float = FIXED_POINT_TOL, atol: float = FIXED_POINT_TOL,
                       tol: float = RESIDUAL_TOL) -> BifurcationPoint | None:
    """The bifurcation of ``kind`` (``"fold"``, ``"flip"`` or ``"torus"``) between two gaits of one branch.

    ``a``, ``b``: (post-impact state, value of ``param``) of two period-``period`` gaits (fixed
    points to ``tol``), e.g. neighbouring points of a sweep, in the order of the branch. The
    kind's test function (ψ_fold = det(A − I), ψ_flip = det(A + I), ψ_torus = det(A ⊙ A − I):
    a real multiplier through +1 or −1, or a complex pair through |μ| = 1) is evaluated at both;
    if it changes sign between them, its zero is located on the branch by the secant method with
    bisection, each iterate corrected onto the branch (:func:`_locate`, the location continuation
    uses, to :data:`LOCATE_TOL` in the parameter). ``None`` when the signs agree (no crossing
    between them, or two), or for ``"torus"`` when the zero is a neutral saddle (a real pair with
    μ₁μ₂ = 1: no bifurcation). ``params``: the other parameters, as in the sweep.
    """
    if kind not in KINDS:
        raise StateError(f"unknown bifurcation kind {kind!r}; known: {', '.join(KINDS)}")
    which = KINDS.index(kind)
    prob = _Problem(system, params, param, period, rtol, atol)
    ends = []
    for x, lam in (a, b):
        u = np.r_[np.asarray(x, float), float(lam)]
        r, J = prob.F(u)
        ends.append((u, J, float(np.max(np.abs(r)))))
    (ua, Ja, ra), (ub, Jb, rb) = ends
    fa, fb = _tests(prob.reduced(ua, Ja))[which], _tests(prob.reduced(ub, Jb))[which]
    if not fa * fb < 0:
        return None
    return _bracketed(prob, ua, ub, kind, tol, (prob.point(ua, Ja, ra, 0.0), fa), (prob.point(ub, Jb, rb, 0.0), fb))


def locate_flip(system: HybridSystem, param: str, a: tuple[Sequence[float], float], b: tuple[Sequence[float], float],
                *, params: Mapping[str, float] | None = None, period: int = 1, rtol: float = FIXED_POINT_TOL,
                atol: float = FIXED_POINT_TOL, tol: float = RESIDUAL_TOL) -> BifurcationPoint | None:
    """The period doubling between two gaits of one branch: where a real multiplier crosses −1
    (:func:`locate_bifurcation` of kind ``"flip"``)."""
    return locate_bifurcation(system, param, a, b, "flip", params=params, period=period, rtol=rtol, atol=atol,
                              tol=tol)


__all__ = ["LOCATE_TOL", "locate_bifurcation", "locate_flip"]
