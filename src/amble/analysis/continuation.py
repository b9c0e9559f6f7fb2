"""Pseudo-arclength continuation of periodic gaits in one parameter, with folds, period
doublings and torus (Neimark–Sacker) points located and the period-doubled branch followed.

A period-k gait at parameter value λ is a zero of

    F(x, λ) = P_k(x; λ) − x,

``P_k`` the k-step post-impact return map on the full state ``x ∈ Rⁿ``. Full state, not section
coordinates: ``P_k`` maps every state onto the section Σ (dimension d), so ``∂P/∂x`` has the d
nontrivial multipliers μᵢ on Σ's tangent space and n − d zeros across it, and ``∂F/∂x = ∂P/∂x − I``
is regular wherever no μᵢ is 1. Both ``∂P/∂x`` and ``∂P/∂λ`` are exact
(:meth:`ReturnMap.derivatives`: variational equations and saltation matrices). The problem and
its corrector are :mod:`amble.analysis.branch_corrector`, the results :mod:`amble.analysis.branch`.

**Pseudo-arclength (Keller).** From a point ``u = (x, λ)`` with unit tangent ``τ`` (the null
vector of ``[F_x F_λ]``), predict ``u + hτ`` and correct by Newton on

    F(u') = 0,    τᵀ(u' − u − hτ) = 0,

whose Jacobian ``[[F_x, F_λ], [τᵀ]]`` stays regular through a fold, where the branch turns back
in λ. The step ``h`` grows by 1.5 after a correction of ≤ 3 Newton iterations and is halved after
a failed one; a step's change of λ is capped (``max_delta``) and so is its length in the state
(3·max_delta·(1 + |x|∞)), so that the branch is drawn finely where it is steep in λ.

**Bifurcations.** Between two points of the branch where a test function of ``A = Uᵀ (∂P/∂x) U``
(``U`` an orthonormal basis of Σ's tangent space; ``A``'s eigenvalues are the multipliers)
changes sign, a fold, flip or torus point is located (:mod:`amble.analysis.bifurcation_location`).

**Branch switching at a flip.** At the flip ``(x*, λ*)`` with ``A v = −v``, the period-2 orbits
branch off as ``x* ± εUv`` (a pitchfork of ``P₂``); the first is found by Newton on
``P₂(x; λ) − x = 0, (Uv)ᵀ(x − x*) = ε`` in ``(x, λ)``, and then continued like any branch.

Units: states in the model's units (rad, rad/s), the parameter in its own, times in s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..errors import AmbleError, ConvergenceError, StateError
from .bifurcation_location import LOCATE_TOL, _bracketed, _tests, locate_bifurcation, locate_flip
from .branch import BifurcationPoint, Branch, BranchPoint
from .branch_corrector import _correct, _null, _Problem
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .multipliers import KINDS

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


def continue_branch(
    system: HybridSystem,
    param: str,
    start: float,
    stop: float,
    *,
    params: Mapping[str, float] | None = None,
    guess: Sequence[float] | None = None,
    period: int | None = None,
    max_delta: float | None = None,
    max_points: int = 400,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
    locate: bool = True,
) -> Branch:
    """Continue the period-``period`` gait from ``param = start`` towards ``stop``; ``period``
    counts footfalls, by default the system's footfall cycle (as :func:`find_fixed_point`).

    The first gait is :func:`find_fixed_point` from ``guess`` (default: the model's) at ``start``.
    The branch is traced by pseudo-arclength until the parameter leaves [start, stop] (the last
    point is then corrected onto ``param = stop`` exactly), ``max_points`` points, or the
    corrector fails at the smallest step (``Branch.end`` says which). ``max_delta``: largest
    change of the parameter per step (default |stop − start| / 50). Folds, flips and torus
    (Neimark–Sacker) points between two points are located (``locate``) to :data:`LOCATE_TOL`;
    ``tol``: the residual ``|P(x) − x|∞`` of every point.
    """
    from .poincare import find_fixed_point

    if not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise StateError(f"continuation needs a finite range START ≠ STOP, got {start}:{stop}")
    prob = _Problem(system, params, param, period, rtol, atol)
    base = {**dict(params or {}), param: start}
    lc = find_fixed_point(system, guess, params=base, period=prob.period, rtol=rtol, atol=atol, tol=tol)
    # a period-k search may land on a period-d orbit (d | k): it is continued as a k-step fixed point
    return _trace(prob, np.r_[lc.fixed_point, start], start, stop, max_delta, max_points, tol, locate,
                  system.name, param, None)


def _trace(prob: _Problem, u: np.ndarray, start: float, stop: float, max_delta: float | None, max_points: int,
           tol: float, locate: bool, name: str, param: str, direction: np.ndarray | None,
           first: BranchPoint | None = None) -> Branch:
    """Pseudo-arclength from the gait ``u`` (already converged) inside [start, stop]."""
    lo, hi = min(start, stop), max(start, stop)
    dmax = max_delta or abs(stop - start) / 50
    names = list(prob.P.k.meta["state_names"][prob.P.mode])
    br = Branch(system=name, param=param, period=prob.period, state_names=names)
    r, J = prob.F(u)
    res = float(np.max(np.abs(r)))
    t = _null(J, direction if direction is not None else np.r_[np.zeros(prob.n), np.sign(stop - start)])
    pt = first or prob.point(u, J, res, 0.0)
    br.points.append(pt)
    tests = _tests(prob.reduced(u, J))
    # the arclength step: the parameter moves at most dmax per step, the state at most about
    # 3·dmax·(1 + |x|) (where the branch is steep in λ, near a fold or a pitchfork's root)
    hmax = 3 * dmax * (1 + float(np.max(np.abs(u[:-1]))))
    h = min(dmax / max(abs(t[-1]), 1e-12), hmax)
    hmin = 1e-8 * h
    while len(br.points) < max_points:
        h = min(h, dmax / max(abs(t[-1]), 1e-12), hmax)
        try:
            un, Jn, resn, it = _correct(prob, u + h * t, t, tol)
        except AmbleError as e:  # ConvergenceError, SimulationError (a fall, a grazing event)
            h *= 0.5
            if h < hmin:
                br.end = f"the corrector failed at the smallest step ({type(e).__name__}: {e})"
                break
            continue
        tn = _null(Jn, t)
        if not lo <= un[-1] <= hi:  # past the end: put the last point on the boundary exactly
            edge = hi if un[-1] > hi else lo
            e = np.r_[np.zeros(prob.n), 1.0]
            try:
                ue, Je, rese, _ = _correct(prob, u + (un - u) * (edge - u[-1]) / (un[-1] - u[-1]), e, tol,
                                           extra=lambda v, edge=edge, e=e: (float(v[-1] - edge), e))
            except AmbleError as ex:
                br.end = f"the corrector failed at the range's end ({ex})"
                break
            un, Jn, resn, tn = ue, Je, rese, _null(Je, t)
        s = br.points[-1].s + float(np.linalg.norm(un - u))
        ptn = prob.point(un, Jn, resn, s)
        testn = _tests(prob.reduced(un, Jn))
        if locate:
            for kind, a, b in zip(KINDS, tests, testn):
                if a * b < 0:
                    bp = _bracketed(prob, u, un, kind, tol, (br.points[-1], a), (ptn, b))
                    if bp is not None:  # None: a neutral saddle, no bifurcation
                        br.bifurcations.append(bp)
        br.points.append(ptn)
        u, t, tests = un, tn, testn
        if not lo < u[-1] < hi:
            br.end = "reached the end of the range"
            break
        h = 1.5 * h if it <= 3 else h
    else:
        br.end = f"{max_points} points"
    return br


def switch_at_flip(system: HybridSystem, flip: BifurcationPoint, param: str, stop: float, *,
                   start: float | None = None, params: Mapping[str, float] | None = None, period: int | None = None,
                   amplitude: float = 1e-3, max_delta: float | None = None, max_points: int = 400,
                   rtol: float = FIXED_POINT_TOL, atol: float = FIXED_POINT_TOL, tol: float = RESIDUAL_TOL,
                   locate: bool = True) -> Branch:
    """The period-doubled branch born at a located flip, continued away from it inside the
    parameter range [start, stop] (default start: the flip's value).

    A supercritical flip's period-doubled branch lies beyond the flip, a subcritical one's before
    it (unstable): the branch goes wherever it lies, ending at the range's ends.
    ``period``: that of the branch the flip was found on (default: the flip's orbit length);
    the new branch has twice that. Its first gait is ``x* + εUv`` corrected with the amplitude
    ``ε = amplitude`` (state units) along the flip's eigenvector held fixed.
    """
    k0 = period or len(flip.point.orbit)
    prob1 = _Problem(system, params, param, k0, rtol, atol)
    x, lam = flip.point.state, flip.point.value
    u = np.r_[x, lam]
    _, J = prob1.F(u)
    U = prob1.tangent_basis(x, lam)
    A = U.T @ (J[:, :-1] + np.eye(prob1.n)) @ U
    w, V = np.linalg.eig(A)
    i = int(np.argmin(np.abs(w + 1)))
    v = U @ np.real(V[:, i])
    v /= np.linalg.norm(v)
    prob = _Problem(system, params, param, 2 * k0, rtol, atol)
    e = np.r_[v, 0.0]
    u1, J1, res, _ = _correct(prob, u + amplitude * e, e, tol,
                              extra=lambda z: (float(e @ (z - u)) - amplitude, e))
    first = lam if start is None else start
    if not min(first, stop) <= u1[-1] <= max(first, stop):
        raise ConvergenceError(f"the period-{2 * k0} branch born at the flip {param} = {lam:.12g} starts at "
                               f"{u1[-1]:.12g}, outside the range {first}:{stop}")
    # continue away from the period-k branch: the tangent's component along v stays positive
    _, Jn = prob.F(u1)
    t = _null(Jn, e)
    return _trace(prob, u1, first, stop, max_delta, max_points, tol, locate, system.name, param, t)


def cascade(system: HybridSystem, param: str, start: float, stop: float, *, levels: int = 3,
            params: Mapping[str, float] | None = None, guess: Sequence[float] | None = None,
            max_delta: float | None = None, rtol: float = FIXED_POINT_TOL, atol: float = FIXED_POINT_TOL,
            tol: float = RESIDUAL_TOL) -> list[Branch]:
    """The period-1 branch and, at each branch's first flip, the period-doubled one: up to
    ``levels`` branches (periods 1, 2, 4, …)."""
    out = [continue_branch(system, param, start, stop, params=params, guess=guess, max_delta=max_delta, rtol=rtol,
                           atol=atol, tol=tol)]
    while len(out) < levels and out[-1].flips():
        br = out[-1]
        try:
            out.append(switch_at_flip(system, br.flips()[0], param, stop, start=start, params=params,
                                      period=br.period,
                                      max_delta=max_delta, rtol=rtol, atol=atol, tol=tol))
        except AmbleError as e:
            br.end += f"; no period-{2 * br.period} branch ({e})"
            break
    return out


__all__ = ["Branch", "BranchPoint", "BifurcationPoint", "LOCATE_TOL", "cascade", "continue_branch",
           "locate_bifurcation", "locate_flip", "switch_at_flip"]
