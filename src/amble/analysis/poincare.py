"""Poincaré return map on the post-impact section, fixed points and Floquet multipliers.

The section of a walker is the set of states just after a footfall. It is a manifold: the new
swing foot is on the ground, and after a mode change (knee locked → unlocked) more coordinates
are tied together. Its tangent space is the image, under the derivative of the reset, of the
tangent space of the guard surface just before impact. We pick the state coordinates that
chart it best (pivoted QR) and drop the dependent ones; the return map in those reduced
coordinates has a non-singular ``A − I`` at a hyperbolic fixed point, and the eigenvalues of
``A`` are the nontrivial Floquet multipliers.

Fixed points are found by damped Newton in the reduced coordinates with a central-difference
Jacobian (each column one compiled return-map evaluation, ~20–50 µs for the compass gait).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..backend.kernels import Kernels, build
from ..errors import ConvergenceError, ModelError, SimulationError, StateError
from ..modelling.hybrid import HybridSystem
from ..simulation.engine import Options, run
from ..simulation.simulate import initial_state, parameter_vector, simulate
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL


@dataclass
class LimitCycle:
    """A periodic gait: fixed point of the (k-step) return map and its stability."""

    system: str
    mode: str
    state_names: list[str]
    fixed_point: np.ndarray
    step_time: float
    multipliers: np.ndarray
    section_coordinates: list[str]
    residual: float
    iterations: int
    period: int
    parameters: dict[str, float]
    jacobian: np.ndarray = field(repr=False)
    hybrid_system: Any = field(default=None, repr=False)

    def trajectory(self, steps: int | None = None) -> Any:
        """Simulate the gait from the fixed point (default: two periods), samples every 5 ms."""
        return simulate(self.hybrid_system, self.fixed_point, params=self.parameters,
                        steps=steps or 2 * self.period, sample_dt=0.005)

    @property
    def stable(self) -> bool:
        """All nontrivial multipliers strictly inside the unit circle."""
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    def to_json(self) -> dict[str, Any]:
        return {
            "system": self.system,
            "mode": self.mode,
            "state_names": self.state_names,
            "fixed_point": self.fixed_point.tolist(),
            "step_time": self.step_time,
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "multiplier_moduli": [float(abs(m)) for m in self.multipliers],
            "stable": self.stable,
            "section_coordinates": self.section_coordinates,
            "residual": self.residual,
            "iterations": self.iterations,
            "period": self.period,
            "parameters": self.parameters,
        }


#: Longest period a k-step return map is built for.
MAX_PERIOD = 64
#: A gait whose points move less than this fraction of the model's size over a period is at rest.
REST_FRACTION = 1e-6


class ReturnMap:
    """The k-step post-impact return map of a walker at fixed parameters.

    ``__call__(x)`` maps a post-impact state to the post-impact state ``k`` footfalls later and
    returns it with the elapsed time; a run that does not complete its steps raises
    :class:`SimulationError` with the outcome.
    """

    def __init__(self, system: HybridSystem, params: Mapping[str, float] | None = None, *, period: int = 1,
                 rtol: float = FIXED_POINT_TOL, atol: float = FIXED_POINT_TOL, mode: str | None = None) -> None:
        if period < 1:
            raise StateError(f"period must be at least 1, got {period}")
        if period > MAX_PERIOD:
            raise StateError(f"period must be at most {MAX_PERIOD}, got {period}")
        if not any(tr.step for tr in system.transitions):
            raise ModelError(f"system {system.name!r} has no step transition: a return map (fixed point, "
                             f"period-k orbit) needs a transition declared with step=True")
        self.system = system
        self.k: Kernels = build(system)
        self.p = parameter_vector(self.k, params, system)
        self.period = period
        self.mode = mode or self.k.meta["modes"][0]
        self.mi = self.k.mode_index(self.mode)
        mst = system.max_step_time
        self.opts = Options(rtol=rtol, atol=atol, max_step_time=mst)
        self.n = self.k.meta["nx"][self.mi]

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        r = run(self.k, self.p, self.mi, np.asarray(x, float), steps=self.period, opts=self.opts)
        if not r.completed:
            raise SimulationError(f"return map: the run did not complete {self.period} step(s) ({r.status})")
        if r.mode != self.mi:
            raise SimulationError("return map: the walker did not come back to the section's mode")
        return r.x, r.t

    def last_impact(self, x: np.ndarray) -> tuple[int, float, np.ndarray]:
        """(transition index, time, pre-event state) of the last footfall when mapping ``x``."""
        r = run(self.k, self.p, self.mi, np.asarray(x, float), steps=self.period, opts=self.opts, record=True,
                sample_dt=1e9)
        if not r.completed:
            raise SimulationError(f"return map: the run did not complete {self.period} step(s) ({r.status})")
        rec = r.recorded
        steps = [i for i, tr in enumerate(rec["etr"]) if self.k.meta["transitions"][int(tr)]["step"]]
        i = steps[-1]
        src = self.k.meta["transitions"][int(rec["etr"][i])]["source"]
        nsrc = self.k.meta["nx"][self.k.mode_index(src)]
        return int(rec["etr"][i]), float(rec["et"][i]), rec["epre"][i][:nsrc].copy()

    def section_basis(self, x: np.ndarray) -> np.ndarray:
        """Orthonormal basis (n × d) of the section's tangent space near the image of ``x``."""
        tr, t, xpre = self.last_impact(x)
        k = self.k
        src = k.mode_index(k.meta["transitions"][tr]["source"])
        gi = [j for j, info in enumerate(k.meta["transitions"]) if info["source"] == k.meta["modes"][src]].index(tr)
        n_pre = xpre.size
        h = 1e-6
        grad = np.zeros(n_pre)
        for j in range(n_pre):
            e = np.zeros(n_pre)
            e[j] = h
            grad[j] = (k.guards(src, t, xpre + e, self.p)[gi] - k.guards(src, t, xpre - e, self.p)[gi]) / (2 * h)
        N = np.linalg.svd(grad[None, :])[2][1:].T  # null space of the guard gradient
        DR = np.zeros((self.n, n_pre))
        for j in range(n_pre):
            e = np.zeros(n_pre)
            e[j] = h
            DR[:, j] = (k.reset(tr, t, xpre + e, self.p)[1] - k.reset(tr, t, xpre - e, self.p)[1]) / (2 * h)
        T = DR @ N
        U, s, _ = np.linalg.svd(T, full_matrices=False)
        d = int(np.sum(s > 1e-7 * s[0]))
        return U[:, :d]


def _chart(U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates that chart the tangent space best, and the map from their increments to states."""
    # pivoted Gram–Schmidt on the rows of U (= QR with column pivoting of Uᵀ): pick, one at a
    # time, the state coordinate whose tangent row is least explained by those already picked
    R = U.copy()
    piv: list[int] = []
    for _ in range(U.shape[1]):
        norms = np.linalg.norm(R, axis=1)
        norms[piv] = -1.0
        j = int(np.argmax(norms))
        piv.append(j)
        v = R[j] / np.linalg.norm(R[j])
        R = R - np.outer(R @ v, v)
    S = np.sort(np.array(piv))
    E = U @ np.linalg.inv(U[S, :])  # n × d: increment of the chart coordinates → tangent vector
    return S, E


def _jacobian(P: ReturnMap, x: np.ndarray, E: np.ndarray, S: np.ndarray, h: float = 1e-5) -> np.ndarray:
    cols = []
    for j in range(E.shape[1]):
        xp, _ = P(x + h * E[:, j])
        xm, _ = P(x - h * E[:, j])
        cols.append((xp - xm)[S] / (2 * h))
    return np.array(cols).T


def default_guess(system: HybridSystem, params: Mapping[str, float] | None = None, steps: int = 30) -> np.ndarray:
    """A fixed-point guess: walk ``steps`` steps from the system's guess (or default start) at
    these parameters and take the last post-impact state; the guess itself if that walk fails."""
    start = system.fixed_point_guess
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
    period: int = 1,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
    max_iter: int = 40,
) -> LimitCycle:
    """Fixed point of the ``period``-step return map, its step time and Floquet multipliers.

    Damped Newton in reduced section coordinates; ``tol`` bounds the residual
    ``|P(x) − x|∞`` of the returned post-impact state.

    Without a ``guess`` the search starts from :func:`default_guess`. At parameters other than
    the defaults, when that search fails or finds an unstable cycle, the model's own gait (its
    guess, on the cycle at the default parameters) is also followed to the requested parameters
    by continuation, and the cycle found that way is returned if it is stable: a walker whose
    default gait is stable finds the stable branch connected to it, not whichever cycle lies
    nearest a poor guess.
    """
    P = ReturnMap(system, params, period=period, rtol=rtol, atol=atol)
    x0 = np.asarray(guess, float) if guess is not None else default_guess(system, params)
    _, x = initial_state(system, P.k, x0, P.mode)
    try:
        direct = _newton(system, P, x, period, tol, max_iter)
    except (SimulationError, ConvergenceError) as e:
        if guess is not None or not params:
            raise ConvergenceError(f"no fixed point from this guess: {e}") from None
        direct = None
    at_defaults = np.array_equal(P.p, np.asarray(P.k.meta["param_defaults"], float))
    if direct is not None and (direct.stable or guess is not None or at_defaults):
        return direct
    found = [direct] if direct is not None else []
    error = None
    for geometric in (False, True):
        try:
            followed = _from_defaults(system, P, x0, geometric, period=period, rtol=rtol, atol=atol, tol=tol,
                                      max_iter=max_iter)
        except ConvergenceError as e:
            error = error or e
            continue
        if followed.stable:
            return followed
        found.append(followed)
    if found:
        return found[0]
    raise error


def _from_defaults(system: HybridSystem, P: ReturnMap, x0: np.ndarray, geometric: bool, stages: int = 16,
                   **kw: Any) -> LimitCycle:
    """The model's own guess lies on the cycle at its default parameters: follow the cycle from
    there to the parameters of ``P`` in stages of ``1/stages`` of the way; a stage that fails is
    halved (down to 1/32 of one), the next after a success doubled back, since cycles can move
    fast near the target; at most ``3 × stages`` searches in all. The parameters move linearly,
    or, with ``geometric``, those positive at both ends geometrically (masses, lengths and
    gravity keep their ratios changing evenly)."""
    defaults = dict(zip(P.k.meta["params"], P.k.meta["param_defaults"]))
    target = dict(zip(P.k.meta["params"], P.p.tolist()))

    def at(s: float) -> dict[str, float]:
        return {k: defaults[k] * (target[k] / defaults[k]) ** s if geometric and defaults[k] > 0 and target[k] > 0
                else defaults[k] + s * (target[k] - defaults[k]) for k in target}

    x = np.asarray(system.fixed_point_guess if system.fixed_point_guess is not None else x0, float)
    done, step, lc = 0.0, 1.0 / stages, None
    for searches in range(1, 3 * stages + 1):
        s = min(1.0, done + step)
        try:
            lc = find_fixed_point(system, x, params=target if s == 1.0 else at(s), **kw)
        except ConvergenceError as e:
            if step < 1.0 / (32 * stages) or searches == 3 * stages:
                raise ConvergenceError(f"no fixed point: continuation from the default parameters failed at "
                                       f"{done:.0%} of the way ({e})") from None
            step /= 2
            continue
        x, done, step = lc.fixed_point, s, min(2 * step, 1.0 / stages)
        if done == 1.0:
            return lc
    raise ConvergenceError(f"no fixed point: continuation from the default parameters reached only {done:.0%} "
                           f"of the way in {3 * stages} searches")


def _newton(system: HybridSystem, P: ReturnMap, x: np.ndarray, period: int, tol: float, max_iter: int) -> LimitCycle:
    y, _ = P(x)  # start on the section
    it = 0
    res = math.inf
    for it in range(1, max_iter + 1):
        Py, T = P(y)
        r = Py - y
        res = float(np.max(np.abs(r)))
        if res < tol:
            break
        S, E = _chart(P.section_basis(y))
        A = _jacobian(P, y, E, S)
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
    xs = y
    Px, T = P(xs)
    _refuse_rest(system, P, xs, T)
    lower = _lower_period(P, xs, period, tol)
    if lower:
        # the k-step orbit is a shorter one repeated: report that one
        return _newton(system, ReturnMap(system, dict(zip(P.k.meta["params"], P.p.tolist())), period=lower,
                                         rtol=P.opts.rtol, atol=P.opts.atol, mode=P.mode), xs, lower, tol, max_iter)
    S, E = _chart(P.section_basis(xs))
    A = _jacobian(P, xs, E, S)
    mult = np.linalg.eigvals(A)
    mult = mult[np.argsort(-np.abs(mult))]
    names = P.k.meta["state_names"][P.mode]
    return LimitCycle(system=system.name, mode=P.mode, state_names=list(names), fixed_point=xs, step_time=T / period,
                      multipliers=mult, section_coordinates=[names[i] for i in S],
                      residual=float(np.max(np.abs(Px - xs))), iterations=it, period=period,
                      parameters=dict(zip(P.k.meta["params"], P.p.tolist())), jacobian=A, hybrid_system=system)


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


def _lower_period(P: ReturnMap, x: np.ndarray, period: int, tol: float) -> int:
    """The smallest proper divisor d of ``period`` with P_d(x) = x (within 100 tol), or 0."""
    for d in range(1, period):
        if period % d:
            continue
        r = run(P.k, P.p, P.mi, x, steps=d, opts=P.opts)
        if r.completed and r.mode == P.mi and np.max(np.abs(r.x - x)) < 100 * tol:
            return d
    return 0
