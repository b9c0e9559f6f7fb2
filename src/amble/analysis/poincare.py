"""Poincaré return map on the post-impact section, fixed points and Floquet multipliers.

Fixed points are found by damped Newton in the reduced coordinates of the section (its chart,
:mod:`amble.analysis.return_map`) with the exact Jacobian of the return map: one compiled run
carries the variational equations along the flow and the saltation matrix through every event
(``backend/_c/sensitivity.h``), so the derivative is that of the integrated map itself, to its
tolerance. Central differences (``jacobian="fd"``) remain as a cross-check.

The return map and its chart of the section are :mod:`amble.analysis.return_map`, the gait found
:mod:`amble.analysis.limit_cycle` (both re-exported here).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ConvergenceError, SimulationError, StateError
from ..simulation.engine import run
from ..simulation.simulate import initial_state, simulate
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .global_starts import GLOBAL_STARTS
from .limit_cycle import LimitCycle
from .mode_cycle import footfalls_per_cycle
from .return_map import CHART_GROWTH, MAX_PERIOD, ReturnMap

if TYPE_CHECKING:
    from ..modelling.hybrid import HybridSystem

__all__ = ["CHART_GROWTH", "MAX_PERIOD", "REST_FRACTION", "LimitCycle", "ReturnMap", "continue_fixed_point",
           "default_guess", "find_fixed_point"]

#: A gait whose points move less than this fraction of the model's size over a period is at rest.
#: Not 0: a passive walker on level ground loses a fraction ~θ² of its energy per impact, so a
#: motion of amplitude θ ≈ 1e-4 has a return-map residual below any tolerance while it decays
#: towards rest (its largest multiplier is 1 − O(θ²)): such a "fixed point" is not a gait.
REST_FRACTION = 1e-3


def default_guess(system: HybridSystem, params: Mapping[str, float] | None = None, steps: int = 30,
                  start: Sequence[float] | None = None) -> np.ndarray:
    """A fixed-point guess: walk ``steps`` steps from ``start`` (default: the system's guess, or
    its default start) at these parameters and take the last post-impact state; the start
    itself if that walk fails. ``steps`` is rounded up to whole footfall cycles
    (:func:`amble.analysis.mode_cycle.footfall_cycle`), so that a walker whose stance feet are
    modes ends in the mode it started in."""
    c = footfalls_per_cycle(system)
    steps = -(-steps // c) * c
    start = system.fixed_point_guess if start is None else start
    if start is None and not system.default_start:
        raise ConvergenceError(f"system {system.name!r} has neither a fixed-point guess nor a default start")
    tr = simulate(system, start, params=params, steps=steps, samples=False)  # events only: bounded memory
    post = tr.final_post_impact_state
    if tr.status == "completed" and post is not None:
        return post
    if start is not None:
        return np.asarray(start, float)
    raise ConvergenceError(f"no fixed-point guess: walking from the default start ended as {tr.status} ({tr.message})")


def find_fixed_point(
    system: HybridSystem,
    guess: Sequence[float] | None = None,
    *,
    params: Mapping[str, float] | None = None,
    period: int | None = None,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
    max_iter: int = 40,
    jacobian: str = "exact",
    collocation: bool = True,
) -> LimitCycle:
    """Fixed point of the ``period``-step return map, its step time and Floquet multipliers.

    ``period`` counts footfalls; by default it is the system's footfall cycle (1 for a one-mode
    walker, 2 for a walker whose stance feet are modes: after one footfall it is in the other
    mode, :func:`amble.analysis.mode_cycle.footfall_cycle`), and a period that is not a multiple
    of that cycle raises :class:`StateError` before any run. The step time is per footfall.

    Damped Newton in reduced section coordinates; ``tol`` bounds the residual
    ``|P(x) − x|∞`` of the returned post-impact state. ``jacobian``: ``"exact"`` (variational
    equations and saltation matrices) or ``"fd"`` (central differences, step 1e-5: a cross-check
    whose error scales with the step squared). A period-k search that lands on an orbit of lower
    period d reports period d and ``requested_period`` k.

    Without a ``guess`` the search starts from :func:`default_guess`. At parameters other than
    the defaults, when that search fails or finds an unstable cycle, the model's own gait (its
    guess, on the cycle at the default parameters) is also followed to the requested parameters
    by continuation (:func:`amble.analysis.homotopy.follow`: tangent predictor from the exact
    parameter derivatives, step control, branch jumps refused, a parameter that only rescales
    time, such as a passive walker's gravity, jumped exactly), and the cycle found that way is
    returned if it is stable: a walker whose default gait is stable finds the stable branch
    connected to it, not whichever cycle lies nearest a poor guess. When both fail (a fold of
    that branch included: another branch may hold a gait), Newton starts from a periodic step
    solved by collocation (:mod:`amble.analysis.collocation_guess`; a passive system only, with
    CasADi). The result's ``found_by`` says which route found it (``"guess"``, ``"walk"``,
    ``"continuation"``, ``"collocation"``) and, for collocation, ``search_note`` why the others
    failed. When nothing is found the error says in one line what each route met (the branch
    folds, the walker fell, the branch was lost, with the last gait found on the way; the
    collocation's failure or why it does not apply). ``collocation=False`` leaves that last
    resort out (a sweep does: its points are continued along their branch, and a failed point is
    reported as such rather than searched for at length).
    """
    if jacobian not in ("exact", "fd"):
        raise StateError(f"jacobian must be 'exact' or 'fd', got {jacobian!r}")
    P = ReturnMap(system, params, period=period, rtol=rtol, atol=atol)
    period = P.period
    at_defaults = np.array_equal(P.p, np.asarray(P.k.meta["param_defaults"], float))
    start = _scaled_start(system, P) if guess is None and not at_defaults else None
    x0 = np.asarray(guess, float) if guess is not None else default_guess(system, params, start=start)
    _, x = initial_state(system, P.k, x0, P.mode)
    try:
        direct = _newton(system, P, x, period, tol, max_iter, jacobian)
    except (SimulationError, ConvergenceError) as e:
        if guess is not None or not params or at_defaults:
            raise ConvergenceError(f"no fixed point from this guess: {e}") from None
        direct, direct_error = None, str(e).splitlines()[0] if str(e) else type(e).__name__
    if direct is not None:
        direct.found_by = "guess" if guess is not None else "walk"
    if direct is not None and (direct.stable or guess is not None or at_defaults):
        return direct
    try:
        followed = _from_defaults(system, P, period=period, tol=tol, max_iter=max_iter, jacobian=jacobian)
    except ConvergenceError as e:
        if direct is not None:
            return direct
        if not collocation:
            raise ConvergenceError(f"{e}; from a walk at these parameters: {direct_error}") from None
        # both searches say why they failed (e.g. the walk at these parameters ends at rest)
        return _by_collocation(system, P, f"{e}; from a walk at these parameters: {direct_error}", tol=tol,
                               max_iter=max_iter, jacobian=jacobian)
    followed.found_by = "continuation"
    return followed if followed.stable or direct is None else direct


def continue_fixed_point(system: HybridSystem, x: Sequence[float], from_params: Mapping[str, float],
                         params: Mapping[str, float], *, period: int | None = None, rtol: float = FIXED_POINT_TOL,
                         atol: float = FIXED_POINT_TOL, tol: float = RESIDUAL_TOL, max_iter: int = 40) -> LimitCycle:
    """The gait ``x`` (a fixed point at ``from_params``) carried to ``params`` along its branch
    (:func:`amble.analysis.homotopy.follow`: tangent predictor from the exact parameter
    derivatives, step control, branch jumps refused). :class:`ConvergenceError` says in one line
    why the branch ends (it folds, the walker falls, it is lost) with the last gait on it."""
    from .homotopy import follow

    P = ReturnMap(system, params, period=period, rtol=rtol, atol=atol)
    period = P.period  # (default: the footfall cycle, as find_fixed_point)
    Q = ReturnMap(system, from_params, period=period, rtol=rtol, atol=atol, mode=P.mode)
    try:
        xe = follow(Q, np.asarray(x, float), Q.p.copy(), P.p.copy(), tol=tol)
    except SimulationError as e:
        raise ConvergenceError(f"lost the branch: {e}") from None
    lc = _newton(system, P, xe, period, tol, max_iter)
    lc.found_by = "continuation"
    return lc


def _scaled_start(system: HybridSystem, P: ReturnMap) -> np.ndarray | None:
    """The model's guess with its velocities rescaled to the requested value of a parameter that
    only rescales time (a passive walker's gravity), when there is one; else ``None``."""
    from .homotopy import time_scaling

    if system.fixed_point_guess is None:
        return None
    p0 = np.asarray(P.k.meta["param_defaults"], float)
    P0 = ReturnMap(system, None, period=P.period, rtol=P.opts.rtol, atol=P.opts.atol, mode=P.mode)
    x = np.asarray(system.fixed_point_guess, float)
    try:
        _, T = P0(x)
    except SimulationError:
        return None
    sc = time_scaling(P0, x, T, p0, P.p)
    return None if sc is None else sc[1]


def _from_defaults(system: HybridSystem, P: ReturnMap, **kw: Any) -> LimitCycle:
    """The model's own guess lies on the cycle at its default parameters: follow that cycle to
    the parameters of ``P`` (:func:`amble.analysis.homotopy.follow`), along the straight path and
    then, if that fails, the geometric one; a parameter that only rescales time jumps first."""
    from .homotopy import follow, time_scaling

    if system.fixed_point_guess is None:
        raise ConvergenceError(f"no fixed point: system {system.name!r} has no gait at its defaults to follow")
    p0 = np.asarray(P.k.meta["param_defaults"], float)
    p1 = P.p.copy()
    Q = ReturnMap(system, None, period=P.period, rtol=P.opts.rtol, atol=P.opts.atol, mode=P.mode)
    x = np.asarray(system.fixed_point_guess, float)
    try:
        _, T = Q(x)
        sc = time_scaling(Q, x, T, p0, p1)
    except SimulationError:
        sc = None
    if sc is not None:
        p0 = p0.copy()
        p0[sc[0]] = p1[sc[0]]
        x = sc[1]
    errors = []
    # with one parameter moving, the geometric path is the straight one run at another pace
    for geometric in (False, True) if int(np.sum(p0 != p1)) > 1 else (False,):
        try:
            xe = follow(Q, x, p0, p1, tol=kw["tol"], geometric=geometric)
            return _newton(system, P, xe, P.period, kw["tol"], kw["max_iter"], kw["jacobian"])
        except (ConvergenceError, SimulationError) as e:
            errors.append(str(e).splitlines()[0] if str(e) else type(e).__name__)
    raise ConvergenceError(f"no fixed point: following the default gait: {errors[0]}")


def _by_collocation(system: HybridSystem, P: ReturnMap, tried: str, **kw: Any) -> LimitCycle:
    """The last resort of :func:`find_fixed_point`: Newton from each registered global start
    (:mod:`amble.analysis.global_starts`: a periodic step solved by collocation,
    :mod:`amble.analysis.collocation_guess`). ``tried`` says in one line why the other searches
    failed; it is the result's ``search_note``, and the error's start when this fails too. Tried
    after a fold of the model's branch as well: a gait found then lies on another branch, which
    the note says."""
    params = dict(zip(P.k.meta["params"], P.p.tolist()))
    for method, starts in GLOBAL_STARTS:
        errors = []
        try:
            for start, x0, why in starts(system, params, P.period):
                if x0 is None:
                    errors.append(f"from {start!r}: {why}")
                    continue
                try:
                    _, x = initial_state(system, P.k, x0, P.mode)
                    lc = _newton(system, P, x, P.period, kw["tol"], kw["max_iter"], kw["jacobian"])
                except (SimulationError, ConvergenceError, StateError) as e:
                    errors.append(f"from {start!r}: Newton from its state: {str(e).splitlines()[0]}")
                    continue
                lc.found_by = method
                lc.search_note = tried
                return lc
        except ConvergenceError as e:
            errors.append(str(e))
        tried = f"{tried}; by {method}: {'; '.join(errors)}"
    raise ConvergenceError(tried)


def _newton(system: HybridSystem, P: ReturnMap, x: np.ndarray, period: int, tol: float, max_iter: int,
            method: str = "exact", requested: int | None = None) -> LimitCycle:
    y, _ = P(x)  # start on the section
    it = 0
    res = math.inf
    for it in range(1, max_iter + 1):
        # exact: the map and its Jacobian in one run (also the multipliers' Jacobian when converged)
        if method == "exact":
            Py, T, A, S, E = P.map_and_section_jacobian(y)
        else:
            Py, T = P(y)
        r = Py - y
        res = float(np.max(np.abs(r)))
        if res < tol:
            break
        if method != "exact":
            A, S, E = P.section_jacobian(y, method)
        try:
            dxi = np.linalg.solve(A - np.eye(len(S)), -r[S])
        except np.linalg.LinAlgError:
            raise ConvergenceError("Newton step failed: a multiplier is 1 (a fold or a neutral direction)") from None
        lam = 1.0
        for _ in range(12):
            trial = y + lam * (E @ dxi)
            try:
                Pt, _ = P(trial)
                if np.max(np.abs(Pt - trial)) < res or lam < 1e-3:
                    y = Pt if np.max(np.abs(Pt - trial)) < res else trial
                    break
            except SimulationError:
                pass
            lam *= 0.5
        else:
            raise ConvergenceError(f"damped Newton stalled at residual {res:.3g} after {it} iterations")
    else:
        raise ConvergenceError(f"no convergence in {max_iter} iterations (residual {res:.3g})")
    xs, Px = y, Py  # the map of the converged state: the last iterate's (the run would repeat it bit for bit)
    _refuse_rest(system, P, xs, T)
    lower = _lower_period(P, xs, period, tol)
    if lower:
        # the k-step orbit is a shorter one repeated: report that one, and that it was asked as k
        return _newton(system, ReturnMap(system, dict(zip(P.k.meta["params"], P.p.tolist())), period=lower,
                                         rtol=P.opts.rtol, atol=P.opts.atol, mode=P.mode), xs, lower, tol, max_iter,
                       method, requested or period)
    if method != "exact":
        A, S, E = P.section_jacobian(xs, method)
    mult = np.linalg.eigvals(A)
    mult = mult[np.argsort(-np.abs(mult))]
    names = P.k.meta["state_names"][P.mode]
    orbit, times = _orbit(P, xs)
    return LimitCycle(system=system.name, mode=P.mode, state_names=list(names), fixed_point=xs, step_time=T / period,
                      multipliers=mult, section_coordinates=[names[i] for i in S],
                      residual=float(np.max(np.abs(Px - xs))), iterations=it, period=period,
                      parameters=dict(zip(P.k.meta["params"], P.p.tolist())), jacobian=A, hybrid_system=system,
                      orbit=orbit, step_times=times, requested_period=requested)


def _orbit(P: ReturnMap, x: np.ndarray) -> tuple[np.ndarray, list[float]]:
    """The post-impact states after each step of one period (the fixed point first) and the
    time of each step."""
    r = run(P.k, P.p, P.mi, x, steps=P.period, opts=P.opts, record=True, events_only=True)
    rec = r.recorded
    step = [i for i, tr in enumerate(rec["etr"]) if P.k.meta["transitions"][int(tr)]["step"]]
    times = np.diff(np.r_[0.0, rec["et"][step]]).tolist()
    points = [x] + [rec["epost"][i][: P.k.meta["nx"][P.mi]] for i in step[:-1]]
    return np.array(points), [float(v) for v in times]


def _refuse_rest(system: HybridSystem, P: ReturnMap, x: np.ndarray, T: float) -> None:
    """A fixed point whose period takes no time or whose points do not move (a walker at rest:
    every residual is tiny because nothing happens) is not a gait. Scale-free: the largest
    displacement over the period, in the world frame, of the named point that moves least, against
    the model's size (the root mean square distance of its points from the stance foot)."""
    if not (T > 0.0):
        raise ConvergenceError(f"the fixed point takes no time per period (step time {T:.3g}): not a gait")
    tr = simulate(system, x, params=dict(zip(P.k.meta["params"], P.p.tolist())), steps=P.period, t_end=2 * T,
                  sample_dt=T / (20 * P.period), rtol=P.opts.rtol, atol=P.opts.atol)
    world = tr.world_points()
    if not world:
        return
    pos = np.stack(list(world.values()), axis=1)  # rows × points × 3
    pos = np.nan_to_num(pos)
    size = math.sqrt(float(np.mean(np.sum(pos[0] ** 2, axis=1))))
    # each point's largest excursion; the least-moving point decides (a relabelled foot jumps
    # by a step even when nothing moves, the hip of a resting walker does not)
    moved = float(np.min(np.max(np.linalg.norm(pos - pos[0], axis=2), axis=0)))
    if size > 0 and moved <= REST_FRACTION * size:
        raise ConvergenceError(f"the fixed point is at rest (its points move {moved:.3g} over a period of "
                               f"{T:.3g} s, the model measures {size:.3g}): not a gait")


def _cycle_length(P: ReturnMap) -> int:
    """Footfalls in the system's footfall cycle from the section's mode (1 when not unique)."""
    return len(P.cycle) if P.cycle else 1


def _lower_period(P: ReturnMap, x: np.ndarray, period: int, tol: float) -> int:
    """The smallest proper divisor d of ``period`` with P_d(x) = x (within 100 tol), or 0. Only
    multiples of the footfall cycle are periods: after another number of footfalls the walker
    is in another mode, where a symmetric gait's state has the fixed point's very numbers (the
    mode check refuses it too, at the price of a run)."""
    c = _cycle_length(P)
    for d in range(c, period, c):
        if period % d:
            continue
        r = run(P.k, P.p, P.mi, x, steps=d, opts=P.opts)
        if r.completed and r.mode == P.mi and np.max(np.abs(r.x - x)) < 100 * tol:
            return d
    return 0
