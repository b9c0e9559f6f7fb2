"""The problem a branch of gaits solves and its Newton corrector.

A period-k gait at parameter value λ is a zero of

    F(x, λ) = P_k(x; λ) − x,

``P_k`` the k-step post-impact return map on the full state ``x ∈ Rⁿ``. Full state, not section
coordinates: ``P_k`` maps every state onto the section Σ (dimension d), so ``∂P/∂x`` has the d
nontrivial multipliers μᵢ on Σ's tangent space and n − d zeros across it, and ``∂F/∂x = ∂P/∂x − I``
is regular wherever no μᵢ is 1. Both ``∂P/∂x`` and ``∂P/∂λ`` are exact
(:meth:`ReturnMap.derivatives`: variational equations and saltation matrices).

:class:`_Problem` holds ``F`` with its exact Jacobian ``[F_x F_λ]``, the reduced matrix
``A = Uᵀ (∂P/∂x) U`` whose eigenvalues are the multipliers, and a gait's orbit; :func:`_correct`
is Newton on ``F = 0`` with one more equation (a hyperplane, or any scalar condition) and
:func:`_null` the oriented tangent of the branch. Apart from :mod:`amble.analysis.continuation`
because tracing a branch, locating a bifurcation on it
(:mod:`amble.analysis.bifurcation_location`) and switching branches all correct onto it so.

Units: states in the model's units (rad, rad/s), the parameter in its own, times in s.

"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ConvergenceError, StateError
from ..simulation.engine import run
from .branch import BranchPoint
from .section import Section

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: Newton iterations of one corrector.
CORRECTOR_ITER = 8


class _Problem:
    """``F(x, λ) = P_k(x; λ) − x`` with its exact Jacobian, and the multipliers of a gait."""

    def __init__(self, system: HybridSystem, params: Mapping[str, float] | None, param: str, period: int | None,
                 rtol: float, atol: float) -> None:
        from .return_map import ReturnMap

        self.P = ReturnMap(system, params, period=period, rtol=rtol, atol=atol)
        names = list(self.P.k.meta["params"])
        if param not in names:
            raise StateError(f"unknown parameter {param!r}; known: {', '.join(names)}")
        self.j = names.index(param)
        self.P.p = self.P.p.copy()
        self.n = self.P.n
        self.period = self.P.period  # (None: the system's footfall cycle)

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
