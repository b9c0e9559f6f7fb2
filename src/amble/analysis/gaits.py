"""Every gait of a walker at one set of parameters: a seeded search with deflation.

:func:`find_fixed_point` finds *one* gait, the one its guess leads to. A walker may have several at
the same parameters — Garcia et al.'s simplest walker has a stable "long-period" gait and an
unstable "short-period" one at every small slope, and past a period doubling the compass gait has
an unstable period-1 gait beside its stable period-2 one. :func:`find_gaits` looks for all gaits of
period 1 … K, stable and unstable, by a search that is reproducible (same arguments, same answer):

1. **Seeds.** Reference states: the model's fixed-point guess and the last post-impact state of a
   walk from its start at these parameters (:func:`default_guess`). Around the first one, a
   Halton set (:func:`halton`, shifted by a seeded random vector) in the section's chart: the section
   coordinates ``x[S]`` (:meth:`Section.coordinates`) are spread over ``x_ref[S] ± spread·scale``
   (``scale_j = |x_ref[S_j]| + 0.1 max|x_ref[S]|``, so a coordinate that is 0 at the reference is
   still varied) and each seed is put back on the post-impact section (:meth:`Section.project`),
   so that every seed is a physically consistent post-impact state. The reference states are
   seeds themselves and come first.
2. **Deflated Newton** (Farrell, Birkisson & Funke 2015) on the full state, ``F(x) = P_k(x) − x``
   with the exact Jacobian ``∂P_k/∂x − I`` (regular on the full state wherever no multiplier is 1:
   the directions across the section have multiplier 0). The residual is multiplied by

       M(x) = ∏ᵢ (1/‖x − xᵢ‖^p + σ),     p = 2, σ = 1,

   over every known point ``xᵢ`` (each point of each gait found so far whose period divides k), so
   Newton cannot converge to a known gait again. The Newton step of ``M F`` is that of ``F`` scaled
   by ``1/(1 − ∇ln M · δ)`` (Sherman–Morrison), which costs nothing beyond the undeflated step. A
   step that makes the walker fall is halved (at most 8 times).
3. **Polish and classify.** A root is refined by :func:`find_fixed_point` (the library's
   exact-Jacobian Newton on the section) to ``tol``, which also refuses a walker at rest, reports a
   period-k root that is a shorter orbit repeated with that shorter period, and gives the
   multipliers. A gait is **new** unless its fixed point lies within ``1e-6 (1 + |x|∞)`` of a point
   of a known gait of the same period: a period-k gait found at any of its k points is one gait.
   After a new gait, the same seed is tried again with it deflated (at most ``per_seed`` gaits
   per seed).

Seeds whose Newton iterates fall (no footfall, the hip below the ground …) or do not converge are
counted, not errors: :class:`Gaits` carries the counts. The search is for period 1, 2, … K in turn,
each using every gait found at a lower period (a period-2 search deflates the period-1 gaits).

A search is evidence, not proof: a gait whose basin of Newton's method contains no seed is missed.
More seeds (``seeds``) and a wider box (``spread``) search more.

Units: states in the model's units (rad, rad/s), step times in the model's time unit.

Reference: P. E. Farrell, Á. Birkisson, S. W. Funke, "Deflation techniques for finding distinct
solutions of nonlinear partial differential equations", SIAM J. Sci. Comput. 37(4), A2026–A2045, 2015.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import AmbleError, ConvergenceError, SimulationError, StateError
from ..simulation.simulate import initial_state
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .limit_cycle import LimitCycle
from .mode_cycle import footfalls_per_cycle, section_period
from .poincare import default_guess, find_fixed_point
from .return_map import MAX_PERIOD, ReturnMap
from .section import Section

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: Deflation power ``p`` and shift ``σ`` (Farrell et al.'s defaults).
POWER, SHIFT = 2.0, 1.0
#: Two fixed points closer than this times ``1 + |x|∞`` are one gait.
SAME_GAIT = 1e-6
#: Residual at which a deflated Newton run hands its root to the polishing search.
ROOT_TOL = 1e-8


class Gaits(list):
    """The gaits found (a list of :class:`LimitCycle`, by period, stable ones first, then by step
    time) and how the search went: ``seeds`` tried, Newton runs that ``fell`` (the walker fell
    during an iterate) or ``diverged`` (no convergence, a singular step, a walker at rest), and
    roots that were ``repeated`` (a gait already known, reached despite the deflation)."""

    system: str
    parameters: dict[str, float]
    max_period: int
    seeds: int
    fell: int
    diverged: int
    repeated: int

    def __init__(self, gaits: Sequence[LimitCycle] = (), **kw: Any) -> None:
        list.__init__(self, gaits)
        for k, v in {"system": "", "parameters": {}, "max_period": 1, "seeds": 0, "fell": 0, "diverged": 0,
                     "repeated": 0, **kw}.items():
            setattr(self, k, v)

    def __repr__(self) -> str:
        kinds = ", ".join(f"period {g.period} {'stable' if g.stable else 'unstable'}" for g in self)
        return f"Gaits({self.system}: {len(self)} found [{kinds}], {self.seeds} seeds)"

    def to_json(self) -> dict[str, Any]:
        return {"system": self.system, "parameters": self.parameters, "gaits": [g.to_json() for g in self],
                "search": {"max_period": self.max_period, "seeds": self.seeds, "fell": self.fell,
                           "diverged": self.diverged, "repeated": self.repeated}}


def find_gaits(
    system: HybridSystem,
    *,
    params: Mapping[str, float] | None = None,
    period: int | None = None,
    tol: float = RESIDUAL_TOL,
    seeds: int | Sequence[Sequence[float]] = 24,
    guesses: Sequence[Sequence[float]] = (),
    spread: float = 0.3,
    seed: int = 0,
    per_seed: int = 3,
    max_iter: int = 30,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    progress: bool | None = None,
) -> Gaits:
    """Every gait of period 1 … ``period`` that the seeded, deflated search finds (module doc).

    Periods count footfalls. A system whose footfalls cycle through c modes (c = 2 for a walker
    whose stance feet are modes, :func:`amble.analysis.mode_cycle.footfall_cycle`) has gaits of
    c, 2c, … footfalls only: those are searched, ``period`` defaults to c, and a ``period`` below
    c raises :class:`StateError`.

    ``params``: parameter overrides; ``tol``: the residual ``|P_k(x) − x|∞`` of every gait
    returned; ``seeds``: the number of Halton seeds around the reference state (besides the
    reference states themselves), or the seeds as full post-impact states (``state_names``
    order); ``guesses``: states tried first, in addition to the seeds; ``spread``: half-width of
    the seed box relative to the reference's section coordinates; ``seed``: the seed of the
    Halton set's shift; ``per_seed``: gaits a seed may yield in turn; ``max_iter``: Newton
    iterations of one run; ``rtol``, ``atol``: integrator tolerances;
    ``progress``: a progress bar (default: on a terminal only).
    """
    c = footfalls_per_cycle(system)
    period = c if period is None else period
    if not 1 <= period <= MAX_PERIOD:
        raise StateError(f"period must be at least 1 and at most {MAX_PERIOD}, got {period}")
    if period < c:
        section_period(system, period)  # says why: the walker is in another mode after fewer footfalls
    if not (tol > 0 and spread >= 0 and per_seed >= 1 and max_iter >= 1):
        raise StateError(f"find_gaits needs tol > 0, spread ≥ 0, per_seed ≥ 1, max_iter ≥ 1; got tol={tol}, "
                         f"spread={spread}, per_seed={per_seed}, max_iter={max_iter}")
    P1 = ReturnMap(system, params, period=c, rtol=rtol, atol=atol)  # the shortest period there is
    names = list(P1.k.meta["params"])
    values = dict(zip(names, P1.p.tolist()))
    starts = [initial_state(system, P1.k, x, P1.mode)[1] for x in guesses]
    starts += _seeds(system, P1, values, seeds, spread, seed)
    out = Gaits(system=system.name, parameters=values, max_period=period, seeds=len(starts))
    from tqdm.auto import tqdm

    periods = range(c, period + 1, c)
    bar = tqdm(total=len(periods) * len(starts), desc=f"gaits of {system.name}", unit="seed",
               disable=None if progress is None else not progress, leave=False)
    try:
        for k in periods:
            Pk = P1 if k == c else ReturnMap(system, values, period=k, rtol=rtol, atol=atol)
            # first beside the shorter gaits, along their flip directions: where a period-k orbit
            # was born of a shorter one, it lies there
            for x0 in _beside(system, out, k, values, rtol, atol):
                _from_seed(system, Pk, k, x0, out, values, tol, per_seed, max_iter, rtol, atol)
            for x0 in starts:
                _from_seed(system, Pk, k, x0, out, values, tol, per_seed, max_iter, rtol, atol)
                bar.update(1)
    finally:
        bar.close()
    out.sort(key=lambda g: (g.period, not g.stable, g.step_time))
    return out


def _from_seed(system: HybridSystem, P: ReturnMap, k: int, x0: np.ndarray, out: Gaits, values: dict[str, float],
               tol: float, per_seed: int, max_iter: int, rtol: float, atol: float) -> None:
    """Deflated Newton from one seed, again after each new gait, at most ``per_seed`` gaits."""
    for _ in range(per_seed):
        known = [pt for g in out if k % g.period == 0 for pt in _points(g)]
        try:
            root = _deflated_newton(P, x0, known, max_iter)
            lc = find_fixed_point(system, root, params=values, period=k, rtol=rtol, atol=atol, tol=tol,
                                  max_iter=max_iter)
        except SimulationError:
            out.fell += 1
            return
        except (ConvergenceError, AmbleError, np.linalg.LinAlgError):
            out.diverged += 1
            return
        if any(g.period == lc.period and _same(lc.fixed_point, g) for g in out):
            out.repeated += 1
            return
        out.append(lc)


def _beside(system: HybridSystem, found: Gaits, k: int, values: dict[str, float], rtol: float, atol: float
            ) -> list[np.ndarray]:
    """Seeds for period ``k`` beside each gait of a period ``d`` that divides ``k`` (``d < k``):
    its fixed point moved by ``±ε v`` along each eigenvector ``v`` of a real negative multiplier
    (a period-2d orbit is born at a flip along it), ``ε`` 1e-3 and 1e-2 of ``1 + |x*|∞``."""
    out: list[np.ndarray] = []
    for g in list(found):
        if g.period >= k or k % g.period:
            continue
        try:
            A, _, E = ReturnMap(system, values, period=g.period, rtol=rtol, atol=atol).section_jacobian(g.fixed_point)
        except AmbleError:
            continue
        w, V = np.linalg.eig(A)
        for i in np.flatnonzero((np.abs(w.imag) < 1e-9) & (w.real < 0)):
            v = E @ np.real(V[:, i])
            v /= float(np.max(np.abs(v)))
            size = 1.0 + float(np.max(np.abs(g.fixed_point)))
            out += [g.fixed_point + sign * eps * size * v for eps in (1e-3, 1e-2) for sign in (1, -1)]
    return out


def _points(g: LimitCycle) -> list[np.ndarray]:
    return list(g.orbit) if g.orbit is not None else [g.fixed_point]


def _same(x: np.ndarray, g: LimitCycle) -> bool:
    near = SAME_GAIT * (1.0 + float(np.max(np.abs(x))))
    return any(float(np.max(np.abs(x - pt))) < near for pt in _points(g))


def _deflation(x: np.ndarray, known: list[np.ndarray]) -> np.ndarray:
    """``∇ln M(x)`` for ``M = ∏ (‖x − xᵢ‖^-p + σ)``."""
    g = np.zeros_like(x)
    for xi in known:
        d = x - xi
        r2 = float(d @ d)
        if r2 == 0.0:
            raise ConvergenceError("a Newton iterate landed on a known gait")
        rp = r2 ** (-POWER / 2)
        g += -POWER * rp / r2 * d / (rp + SHIFT)
    return g


def _deflated_newton(P: ReturnMap, x: np.ndarray, known: list[np.ndarray], max_iter: int) -> np.ndarray:
    """A root of ``M(x) (P(x) − x)``: Newton with the exact Jacobian, each step scaled for the
    deflation, capped at a tenth of the state's size, and halved while it makes the walker fall
    or does not decrease ``|M F|∞``. Raises :class:`SimulationError` when the walker falls from
    the start or every step tried, :class:`ConvergenceError` when there is no root."""
    eye = np.eye(len(x))
    x = np.asarray(x, float).copy()
    Px, _, s = P.derivatives(x, params=False)
    F = Px - x
    for _ in range(max_iter):
        res = float(np.max(np.abs(F)))
        if res < ROOT_TOL:
            return x
        delta = np.linalg.solve(s.dx_dx0 - eye, -F)
        denom = 1.0 - float(_deflation(x, known) @ delta) if known else 1.0
        if not np.isfinite(denom) or abs(denom) < 1e-14:
            raise ConvergenceError("the deflated Newton step is singular")
        step = delta / denom
        # a long step leaves the gait's neighbourhood and the walker falls: cap it
        size, cap = float(np.max(np.abs(step))), 0.1 * (1.0 + float(np.max(np.abs(x))))
        if size > cap:
            step *= cap / size
        merit = _deflated_size(x, F, known)
        lam, fell = 1.0, None
        for _ in range(10):
            trial = x + lam * step
            try:  # the map alone: its derivatives only at the step taken
                Pt, _ = P(trial)
            except SimulationError as e:
                fell, lam = e, lam * 0.5
                continue
            if _deflated_size(trial, Pt - trial, known) < merit:
                break
            lam *= 0.5
        else:  # no step of 1/512 of Newton's decreases the deflated residual: a dead end
            if fell is not None:
                raise fell
            raise ConvergenceError(f"the deflated Newton iteration stalled at residual {res:.3g}")
        x = trial
        Px, _, s = P.derivatives(x, params=False)
        F = Px - x
    raise ConvergenceError(f"the deflated Newton iteration did not converge in {max_iter} iterations")


def _deflated_size(x: np.ndarray, F: np.ndarray, known: list[np.ndarray]) -> float:
    """``|M(x) F|∞``, the merit of the line search."""
    m = 1.0
    for xi in known:
        r = float(np.linalg.norm(x - xi))
        m *= (r ** -POWER if r > 0 else np.inf) + SHIFT
    return m * float(np.max(np.abs(F)))


#: The first primes: the bases of the Halton sequence, one per section coordinate.
_PRIMES = (2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97, 101,
           103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193, 197, 199)


def halton(n: int, d: int, seed: int | None = 0) -> np.ndarray:
    """``n`` points of the Halton sequence in ``[0, 1)^d`` (radical inverses in the first ``d``
    primes, from index 1), each coordinate rotated by a uniform shift drawn from ``seed``
    (Cranley–Patterson, modulo 1; ``None``: no shift): low-discrepancy, reproducible. For d above
    46 the bases repeat (with a shift, the points are then merely a seeded set)."""
    shift = np.random.default_rng(seed).random(d) if seed is not None else np.zeros(d)
    out = np.empty((n, d))
    for j in range(d):
        base = _PRIMES[j % len(_PRIMES)]
        for i in range(n):
            f, r, m = 1.0, 0.0, i + 1
            while m:
                f /= base
                r += f * (m % base)
                m //= base
            out[i, j] = r
    return (out + shift) % 1.0


def _references(system: HybridSystem, P: ReturnMap, values: dict[str, float]) -> list[np.ndarray]:
    """The model's fixed-point guess and the end of a walk from its start at these parameters."""
    refs: list[np.ndarray] = []
    if system.fixed_point_guess is not None:
        refs.append(initial_state(system, P.k, system.fixed_point_guess, P.mode)[1])
    try:
        walked = initial_state(system, P.k, default_guess(system, values), P.mode)[1]
    except AmbleError:
        walked = None
    if walked is not None and not any(np.allclose(walked, r, rtol=0, atol=1e-12) for r in refs):
        refs.append(walked)
    if not refs:
        raise ConvergenceError(f"system {system.name!r} has neither a fixed-point guess nor a start to seed a "
                               f"gait search from; give seeds")
    return refs


def _seeds(system: HybridSystem, P: ReturnMap, values: dict[str, float], seeds: int | Sequence[Sequence[float]],
           spread: float, seed: int) -> list[np.ndarray]:
    """The reference states and ``seeds`` Halton points around the first one on the section; or the
    seeds given, as full states."""
    if not isinstance(seeds, (int, np.integer)):
        given = [initial_state(system, P.k, x, P.mode)[1] for x in seeds]
        if not given:
            raise StateError("seeds: give at least one state, or a number of seeds")
        return given
    if seeds < 0:
        raise StateError(f"seeds must be a non-negative number or a list of states, got {seeds}")
    refs = _references(system, P, values)
    if seeds == 0:
        return refs
    ref = refs[0]
    try:
        section = Section.of(P, ref)
        S = section.coordinates()
    except AmbleError:  # the reference falls at these parameters: vary every coordinate, unprojected
        section, S = None, np.arange(len(ref))
    scale = np.abs(ref[S]) + 0.1 * float(np.max(np.abs(ref[S])))
    u = halton(seeds, len(S), seed)
    out = list(refs)
    for row in u:
        x = ref.copy()
        x[S] = ref[S] + spread * scale * (2 * row - 1)
        if section is not None:
            try:
                x = section.project(x, S)
            except AmbleError:
                pass  # no section state with these coordinates near the reference: the seed as drawn
        out.append(x)
    return out


__all__ = ["Gaits", "find_gaits", "halton"]
