"""Pseudo-arclength continuation of periodic gaits in one parameter, with folds, period
doublings and torus (Neimark–Sacker) points located and the period-doubled branch followed.

A period-k gait at parameter value λ is a zero of

    F(x, λ) = P_k(x; λ) − x,

``P_k`` the k-step post-impact return map on the full state ``x ∈ Rⁿ``. Full state, not section
coordinates: ``P_k`` maps every state onto the section Σ (dimension d), so ``∂P/∂x`` has the d
nontrivial multipliers μᵢ on Σ's tangent space and n − d zeros across it, and ``∂F/∂x = ∂P/∂x − I``
is regular wherever no μᵢ is 1. Both ``∂P/∂x`` and ``∂P/∂λ`` are exact
(:meth:`ReturnMap.derivatives`: variational equations and saltation matrices).

**Pseudo-arclength (Keller).** From a point ``u = (x, λ)`` with unit tangent ``τ`` (the null
vector of ``[F_x F_λ]``), predict ``u + hτ`` and correct by Newton on

    F(u') = 0,    τᵀ(u' − u − hτ) = 0,

whose Jacobian ``[[F_x, F_λ], [τᵀ]]`` stays regular through a fold, where the branch turns back
in λ. The step ``h`` grows by 1.5 after a correction of ≤ 3 Newton iterations and is halved after
a failed one; a step's change of λ is capped (``max_delta``) and so is its length in the state
(3·max_delta·(1 + |x|∞)), so that the branch is drawn finely where it is steep in λ.

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

**Branch switching at a flip.** At the flip ``(x*, λ*)`` with ``A v = −v``, the period-2 orbits
branch off as ``x* ± εUv`` (a pitchfork of ``P₂``); the first is found by Newton on
``P₂(x; λ) − x = 0, (Uv)ᵀ(x − x*) = ε`` in ``(x, λ)``, and then continued like any branch.

Units: states in the model's units (rad, rad/s), the parameter in its own, times in s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import AmbleError, ConvergenceError, StateError
from ..simulation.engine import run
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .multipliers import KINDS, crossing_functions, resonance, torus_pair
from .section import Section

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: A located bifurcation's parameter is known to this (parameter units) or better.
LOCATE_TOL = 1e-12
#: Newton iterations of one corrector.
CORRECTOR_ITER = 8


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


class _Problem:
    """``F(x, λ) = P_k(x; λ) − x`` with its exact Jacobian, and the multipliers of a gait."""

    def __init__(self, system: HybridSystem, params: Mapping[str, float] | None, param: str, period: int,
                 rtol: float, atol: float) -> None:
        from .poincare import ReturnMap

        self.P = ReturnMap(system, params, period=period, rtol=rtol, atol=atol)
        names = list(self.P.k.meta["params"])
        if param not in names:
            raise StateError(f"unknown parameter {param!r}; known: {', '.join(names)}")
        self.j = names.index(param)
        self.P.p = self.P.p.copy()
        self.n = self.P.n
        self.period = period

    def at(self, lam: float) -> None:
        self.P.p[self.j] = lam

    def F(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``F(u)`` and ``[F_x F_λ]`` (n × n+1)."""
        self.at(u[-1])
        Px, _, s = self.P.derivatives(u[:-1], params=True)
        J = np.hstack([s.dx_dx0 - np.eye(self.n), s.dx_dp[:, [self.j]]])
        return Px - u[:-1], J

    def tangent_basis(self, x: np.ndarray, lam: float) -> np.ndarray:
        self.at(lam)
        return Section.of(self.P, x).tangent()

    def reduced(self, u: np.ndarray, J: np.ndarray) -> np.ndarray:
        """``A = Uᵀ ∂P/∂x U`` at a gait ``u``: its eigenvalues are the nontrivial multipliers."""
        U = self.tangent_basis(u[:-1], u[-1])
        return U.T @ (J[:, :-1] + np.eye(self.n)) @ U

    def point(self, u: np.ndarray, J: np.ndarray, res: float, s: float) -> BranchPoint:
        A = self.reduced(u, J)
        mult = np.linalg.eigvals(A)
        mult = mult[np.argsort(-np.abs(mult))]
        orbit, times = self.orbit(u)
        return BranchPoint(value=float(u[-1]), state=u[:-1].copy(), orbit=orbit, step_times=times, multipliers=mult,
                           residual=res, s=s)

    def orbit(self, u: np.ndarray) -> tuple[np.ndarray, list[float]]:
        self.at(u[-1])
        P = self.P
        r = run(P.k, P.p, P.mi, u[:-1], steps=P.period, opts=P.opts, record=True, events_only=True)
        rec = r.recorded
        step = [i for i, tr in enumerate(rec["etr"]) if P.k.meta["transitions"][int(tr)]["step"]]
        times = np.diff(np.r_[0.0, rec["et"][step]]).tolist()
        pts = [u[:-1]] + [rec["epost"][i][: P.n] for i in step[:-1]]
        return np.array(pts), [float(v) for v in times]


def _tests(A: np.ndarray) -> tuple[float, float, float]:
    """(ψ_fold, ψ_flip, ψ_torus) = (det(A − I), det(A + I), det(A ⊙ A − I)), in ``KINDS`` order."""
    return crossing_functions(A)


def _null(J: np.ndarray, prev: np.ndarray | None) -> np.ndarray:
    """Unit null vector of the n × (n+1) Jacobian, oriented along ``prev``."""
    t = np.linalg.svd(J)[2][-1]
    if prev is not None and float(t @ prev) < 0:
        t = -t
    return t


def _correct(prob: _Problem, u0: np.ndarray, normal: np.ndarray, tol: float, extra: Any = None
             ) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Newton on ``F(u) = 0, normalᵀ(u − u0) = 0`` (or ``extra(u) → (value, gradient)`` as the last
    equation). Returns the gait, ``[F_x F_λ]`` there, the residual and the iterations; raises
    :class:`ConvergenceError` (or the simulation's error) when it does not converge."""
    u = u0.copy()
    for it in range(1, CORRECTOR_ITER + 1):
        r, J = prob.F(u)
        res = float(np.max(np.abs(r)))
        c, g = extra(u) if extra is not None else (float(normal @ (u - u0)), normal)
        if res < tol and it > 1:
            return u, J, res, it
        du = np.linalg.solve(np.vstack([J, g[None, :]]), -np.r_[r, c])
        u = u + du
        if not np.all(np.isfinite(u)):
            break
        if float(np.max(np.abs(du))) < 1e-3 * tol and res < 10 * tol:
            r, J = prob.F(u)
            return u, J, float(np.max(np.abs(r))), it
    raise ConvergenceError("the corrector did not converge")


def continue_branch(
    system: HybridSystem,
    param: str,
    start: float,
    stop: float,
    *,
    params: Mapping[str, float] | None = None,
    guess: Sequence[float] | None = None,
    period: int = 1,
    max_delta: float | None = None,
    max_points: int = 400,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
    locate: bool = True,
) -> Branch:
    """Continue the period-``period`` gait from ``param = start`` towards ``stop``.

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
    lc = find_fixed_point(system, guess, params=base, period=period, rtol=rtol, atol=atol, tol=tol)
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
