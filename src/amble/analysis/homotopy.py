"""Following a gait from parameters where it is known to parameters where it is wanted.

A gait known at parameters ``p₀`` (the model's own, at its defaults) is carried to ``p₁`` along
the straight path ``p(s) = p₀ + s (p₁ − p₀)``, ``s ∈ [0, 1]`` (or, with ``geometric``, each
parameter positive at both ends moves as ``p₀ (p₁/p₀)^s``: masses, lengths and gravity keep
their ratios changing evenly). The gaits along the path are the zeros of

    F(x, s) = P(x; p(s)) − x,

``P`` the post-impact return map on the full state. Its Jacobian ``[∂P/∂x − I, (∂P/∂p) p'(s)]``
is exact (variational equations and saltation matrices), and so is the tangent of the branch,
its null vector. Each step predicts along the tangent and corrects by Newton on ``F = 0`` in the
hyperplane normal to it (pseudo-arclength), so the path is followed through steep parts, and a
fold — where ``s`` turns back — is seen and reported rather than stepped over.

**Branch jumps.** A corrected point must agree with its prediction: the distance of the
corrected ``(x, s)`` from the predicted one at most :data:`JUMP_FRACTION` of the step (a smooth
branch bends by O(h²)), the step time within :data:`JUMP_TIME` (relative) of the one predicted
from the exact ``∂T/∂(x, s)``, and the nontrivial multipliers within :data:`JUMP_MULTIPLIER` of
the last point's. Otherwise the step is halved: a large step that lands on another cycle (an
unstable one nearby, say) is refused, not followed.

**Gravity's time scaling.** A passive walker's gait at gravity ``g`` is one at ``g'`` with the
same angles, the velocities scaled by ``√(g'/g)`` and the step time by ``√(g/g')``: the
equations of motion ``M q̈ + C(q, q̇) q̇ + G(q) g = 0`` and a velocity-linear impact keep that
form. Which parameter (if any) scales so is not read from names: :func:`time_scaling` checks it on
the return map itself (the scaled known gait must be a gait at the new value, to 1e-7, and its step
time scaled exactly), so a controller with its own time constants, a damper or a spring simply
has no such parameter. That parameter then jumps to its target for free before the path starts.

Units: states in the model's units (rad, rad/s), times in s, parameters in their own.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import ConvergenceError, SimulationError
from .section import Section

#: ``P`` below: a :class:`amble.analysis.poincare.ReturnMap` (not imported: poincare calls this module).
ReturnMap = Any

#: A corrected point may lie at most this fraction of the step from its prediction.
JUMP_FRACTION = 0.3
#: ... and its step time within this relative distance of the predicted one.
JUMP_TIME = 0.05
#: ... and each multiplier within this distance of the last point's (a jump to another cycle
#: changes them by O(1); along a branch they move by O(h)).
JUMP_MULTIPLIER = 0.25
#: Longest step in s (the path's fraction), the smallest before giving up, and Newton iterations.
MAX_DS = 0.125
MIN_STEP = 1e-6
CORRECTOR_ITER = 8
#: Residual to which the points along a path are corrected, at least (the caller's ``tol`` if
#: larger): they are predictions' bases, not results — the end is polished by the caller's Newton.
#: Far from the defaults the return map holds only about 1e-12 (a compass gait at mh = 2.5,
#: m = 0.48, a = 0.08, slope 0.18: Newton stalls at 1.8e-12), and a path corrected to 1e-12 there was
#: "lost" with its gait in hand.
CORRECTOR_TOL = 1e-10
#: Steps along one path, at most.
MAX_STEPS = 400
#: Relative residual below which a scaled gait counts as a gait (the symmetry holds).
SCALING_TOL = 1e-7


def _velocity_mask(names: list[str]) -> np.ndarray | None:
    """Which state entries are velocities (``<coordinate>_dot`` of a coordinate in the state);
    ``None`` when some entry is neither (e.g. a controller's state): no time scaling then."""
    coords = {n for n in names if not n.endswith("_dot")}
    mask = np.array([n.endswith("_dot") and n[:-4] in coords for n in names])
    if int(mask.sum()) * 2 != len(names):
        return None
    return mask


def time_scaling(P: ReturnMap, x: np.ndarray, T: float, p0: np.ndarray,
                 p1: np.ndarray) -> tuple[int, np.ndarray] | None:
    """A parameter that scales time (gravity in a passive walker), checked on the map.

    ``x`` is a gait (period ``T``) of ``P`` at ``p0``. For each parameter positive in both ``p0``
    and ``p1`` and changed between them, the state with velocities scaled by ``√(p1/p0)`` must be
    a gait at the changed value with step time scaled by ``√(p0/p1)``. Returns (that
    parameter's index, the scaled gait), or ``None``."""
    mask = _velocity_mask(list(P.k.meta["state_names"][P.mode]))
    if mask is None:
        return None
    saved = P.p.copy()
    try:
        for j in np.flatnonzero((p0 != p1) & (p0 > 0) & (p1 > 0)):
            k = float(p1[j] / p0[j])
            xs = np.where(mask, x * math.sqrt(k), x)
            P.p = p0.copy()
            P.p[j] = p1[j]
            try:
                Px, Ts = P(xs)
            except SimulationError:
                continue
            scale = max(1.0, float(np.max(np.abs(xs))))
            if (np.max(np.abs(Px - xs)) < SCALING_TOL * scale
                    and abs(Ts - T / math.sqrt(k)) < SCALING_TOL * max(T, 1.0)):
                return int(j), xs
        return None
    finally:
        P.p = saved


class _Path:
    """``F(x, s) = P(x; p(s)) − x`` with its exact Jacobian and the step time's derivative."""

    def __init__(self, P: ReturnMap, p0: np.ndarray, p1: np.ndarray, geometric: bool) -> None:
        self.P, self.p0, self.p1 = P, p0, p1
        self.geo = geometric & (p0 > 0) & (p1 > 0)
        self.n = P.n

    def params(self, s: float) -> np.ndarray:
        lin = self.p0 + s * (self.p1 - self.p0)
        with np.errstate(divide="ignore", invalid="ignore"):
            geo = self.p0 * (self.p1 / self.p0) ** s
        return np.where(self.geo, geo, lin)

    def dparams(self, s: float) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            dgeo = self.params(s) * np.log(self.p1 / self.p0)
        return np.where(self.geo, dgeo, self.p1 - self.p0)

    def F(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
        """``F(u)``, ``[F_x F_s]`` (n × n+1), the step time ``T`` and ``[T_x T_s]``."""
        s = float(u[-1])
        self.P.p = self.params(s)
        Px, T, sens = self.P.derivatives(u[:-1], params=True)
        dp = self.dparams(s)
        J = np.hstack([sens.dx_dx0 - np.eye(self.n), (sens.dx_dp @ dp)[:, None]])
        dT = np.r_[sens.dt_dx0, float(sens.dt_dp @ dp)]
        return Px - u[:-1], J, float(T), dT

    def multipliers(self, u: np.ndarray, J: np.ndarray) -> np.ndarray:
        self.P.p = self.params(float(u[-1]))
        U = Section.of(self.P, u[:-1]).tangent()
        return np.linalg.eigvals(U.T @ (J[:, :-1] + np.eye(self.n)) @ U)

    def where(self, s: float, names: list[str]) -> str:
        """The parameters at ``s`` that move along the path, as ``name = value`` text."""
        p = self.params(s)
        moved = [f"{nm} = {v:.6g}" for nm, v, a, b in zip(names, p, self.p0, self.p1) if a != b]
        return ", ".join(moved) or "the start"


def _null(J: np.ndarray, prev: np.ndarray) -> np.ndarray:
    t = np.linalg.svd(J)[2][-1]
    return -t if float(t @ prev) < 0 else t


def _correct(path: _Path, u0: np.ndarray, normal: np.ndarray, tol: float, fix_s: float | None = None
             ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray, int]:
    """Newton on ``F = 0`` and ``normalᵀ(u − u0) = 0`` (or ``s = fix_s``)."""
    u = u0.copy()
    e = np.r_[np.zeros(path.n), 1.0]
    for it in range(1, CORRECTOR_ITER + 1):
        r, J, T, dT = path.F(u)
        res = float(np.max(np.abs(r)))
        if res < tol and it > 1:
            return u, J, T, dT, it
        c, g = (float(u[-1] - fix_s), e) if fix_s is not None else (float(normal @ (u - u0)), normal)
        u = u + np.linalg.solve(np.vstack([J, g[None, :]]), -np.r_[r, c])
        if not np.all(np.isfinite(u)):
            break
    raise ConvergenceError(f"Newton did not converge (residual {res:.3g})")


def _spread(a: np.ndarray, b: np.ndarray) -> float:
    """The largest distance from a multiplier of one set to the nearest of the other, the
    largest in modulus of each compared (the section's dimension may change along a path, where
    a parameter reaches 0, adding or dropping a multiplier 0)."""
    k = min(len(a), len(b))
    if k == 0:
        return 0.0
    a, b = a[np.argsort(-np.abs(a))][:k], b[np.argsort(-np.abs(b))][:k]
    d = np.abs(a[:, None] - b[None, :])
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def follow(P: ReturnMap, x: np.ndarray, p0: np.ndarray, p1: np.ndarray, *, tol: float,
           geometric: bool = False) -> np.ndarray:
    """Carry the gait ``x`` of ``P`` at ``p0`` to ``p1``; returns the gait at ``p1`` (full state,
    a zero of ``F`` to ``tol``, or :data:`CORRECTOR_TOL` if larger: polish it with Newton). ``P.p``
    is left at ``p1``.

    Raises :class:`ConvergenceError` with one line saying what happened and the last good gait:
    the branch folds (``s`` turns back: no gait beyond on this branch), the walker fell, or the
    branch was lost (no step down to :data:`MIN_STEP` was accepted).
    """
    names = list(P.k.meta["params"])
    tol = max(tol, CORRECTOR_TOL)
    path = _Path(P, np.asarray(p0, float), np.asarray(p1, float), geometric)
    u = np.r_[np.asarray(x, float), 0.0]
    r, J, T, dT = path.F(u)
    if float(np.max(np.abs(r))) >= tol:
        u, J, T, dT, _ = _correct(path, u, np.r_[np.zeros(path.n), 1.0], tol, fix_s=0.0)
    t = _null(J, np.r_[np.zeros(path.n), 1.0])
    mult = path.multipliers(u, J)
    h = MAX_DS / max(abs(t[-1]), 1e-12)
    hmax = 8 * h
    why = ""

    def last() -> str:
        return (f"last gait at {path.where(float(u[-1]), names)} ({u[-1]:.0%} of the way): "
                f"x = [{', '.join(f'{v:.6g}' for v in u[:-1])}], step time {T:.6g} s")

    for _ in range(MAX_STEPS):
        h = min(h, MAX_DS / max(abs(t[-1]), 1e-12), hmax)
        up = u + h * t
        end = up[-1] >= 1.0
        if end:  # the last step lands on s = 1 exactly
            h_end = (1.0 - u[-1]) / t[-1]
            up = u + h_end * t
        try:
            un, Jn, Tn, dTn, it = _correct(path, up, t, tol, fix_s=1.0 if end else None)
        except (ConvergenceError, SimulationError, np.linalg.LinAlgError) as e:
            why = "the walker fell" if "fell" in str(e) else f"no gait ({str(e).splitlines()[0]})"
            h *= 0.5
            if h < MIN_STEP:
                break
            continue
        step = float(np.linalg.norm(up - u))
        Tp = T + dT @ (up - u)
        multn = path.multipliers(un, Jn)
        jump = (float(np.linalg.norm(un - up)) > JUMP_FRACTION * max(step, 1e-12)
                or abs(Tn - Tp) > JUMP_TIME * abs(Tn) or _spread(multn, mult) > JUMP_MULTIPLIER)
        if jump:
            why = "each corrected gait left the predicted branch (another cycle nearby)"
            h *= 0.5
            if h < MIN_STEP:
                break
            continue
        tn = _null(Jn, t)
        if tn[-1] * t[-1] < 0 and not end:
            # s turns back between the two gaits: the fold lies at or beyond the larger s
            fold = max(float(u[-1]), float(un[-1]))
            raise ConvergenceError(f"the branch folds at {path.where(fold, names)} ({fold:.0%} of the way); no gait "
                                   f"beyond on this branch; {last()}")
        u, J, T, dT, t, mult = un, Jn, Tn, dTn, tn, multn
        if end:
            P.p = path.params(1.0)
            return u[:-1]
        h = 1.5 * h if it <= 3 else h
    else:
        why = f"{MAX_STEPS} steps did not reach the end"
    if why == "the walker fell":
        raise ConvergenceError(f"the walker fell just beyond {path.where(float(u[-1]), names)} at every step size; "
                               f"{last()}")
    raise ConvergenceError(f"lost the branch after {path.where(float(u[-1]), names)} ({why}); {last()}")


__all__ = ["follow", "time_scaling"]
