"""The Poincaré section of a hybrid system, derived from its step transition's guard and reset.

A step transition ``tr`` leaves mode ``s`` where its guard ``g(t, x⁻; p)`` reaches zero and
enters the section's mode through its reset ``x⁺ = Δ(t, x⁻; p)``. The post-impact section is
the image of the guard surface,

    Σ = { Δ(t, y; p) : g(t, y; p) = 0 },

a manifold of dimension ``d`` (``n_s − 1`` when the reset is one-to-one on the guard surface;
less when it collapses directions, e.g. a plastic impact that locks a joint). Its tangent space at
``Δ(y)`` is ``DΔ · ker ∇g``; the state coordinates that chart it best (pivoted Gram–Schmidt on
the rows of an orthonormal tangent basis) are its *section coordinates*. Nothing here is keyed on
the name of a coordinate or a parameter: the section comes from the compiled guard, reset and
their exact Jacobians (``Kernels.surface_gradients``, ``Kernels.reset_jacobian``).

**Projection.** A state ``x`` of the section's mode is put on Σ by keeping its section
coordinates ``x[S]`` and solving for the rest: Newton (Gauss–Newton when the system is not
square) in the pre-impact state ``y`` on

    g(t, y; p) = 0,    Δ(t, y; p)[S] = x[S],

whose Jacobian ``[∇g; DΔ[S, :]]`` is exact. We project along the guard (through its pre-image)
rather than along the flow because a post-impact state is not near the guard of its own mode:
flowing to the next zero of ``g`` would move it a whole step. Keeping the chart coordinates
keeps what a user set — the two axes of a basin grid stay the values of the grid — and the map
``ξ ↦ Δ(y(ξ))`` is the chart's inverse, so the solution is unique near the reference state.

Units: those of the model's states (angles in rad, angular velocities in rad/s).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..backend.library import Kernels
from ..errors import ConvergenceError, ModelError, StateError

#: Relative singular-value threshold below which a tangent direction of the section is dropped.
RANK_TOL = 1e-7
#: Residual ``max(|g|, |Δ[S] − x[S]|)`` at which a projection has converged (state units).
PROJECT_TOL = 1e-12


def chart(U: np.ndarray, prefer: Sequence[int] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates that chart the tangent space ``span U`` best, and the map from their increments
    to tangent vectors.

    ``U``: n × d orthonormal basis. Returns ``S`` (d sorted state indices) and ``E`` (n × d, with
    ``E[S, :] = I``). Pivoted Gram–Schmidt on the rows of ``U`` (QR with column pivoting of
    ``Uᵀ``): the coordinates in ``prefer`` are taken first (refused with :class:`StateError` when
    they are not independent on the section), then, one at a time, the coordinate whose tangent
    row is least explained by those already picked.
    """
    R = np.array(U, float, copy=True)
    scale = float(np.max(np.linalg.norm(R, axis=1))) if R.size else 0.0
    piv: list[int] = []
    for j in prefer:
        if len(piv) == U.shape[1] or np.linalg.norm(R[j]) < 1e-6 * max(scale, 1e-300):
            raise StateError(f"state coordinate {j} does not chart the section together with {piv}: "
                             f"it is tied to them on the section")
        piv.append(int(j))
        v = R[j] / np.linalg.norm(R[j])
        R = R - np.outer(R @ v, v)
    while len(piv) < U.shape[1]:
        norms = np.linalg.norm(R, axis=1)
        norms[piv] = -1.0
        j = int(np.argmax(norms))
        piv.append(j)
        v = R[j] / np.linalg.norm(R[j])
        R = R - np.outer(R @ v, v)
    S = np.sort(np.array(piv, dtype=int))
    E = U @ np.linalg.inv(U[S, :])  # increment of the chart coordinates → tangent vector
    return S, E


class Section:
    """The post-impact section of one step transition at fixed parameters, near a reference.

    ``k``: compiled kernels; ``p``: parameter vector (kernel order); ``transition``: index of the
    step transition; ``t``: the event time used for time-dependent guards and resets (s);
    ``pre``: a pre-impact state near the guard surface (the source mode's length), the starting
    point of every projection. ``ReturnMap.last_impact`` supplies all three.
    """

    def __init__(self, k: Kernels, p: np.ndarray, transition: int, t: float, pre: np.ndarray) -> None:
        self.k, self.p, self.tr, self.t = k, np.asarray(p, float), int(transition), float(t)
        info = k.meta["transitions"][self.tr]
        self.source = k.mode_index(info["source"])
        self.target = k.mode_index(info["target"]) if info["target"] else self.source
        src = k.meta["modes"][self.source]
        self.row = [j for j, ti in enumerate(k.meta["transitions"]) if ti["source"] == src].index(self.tr)
        self.pre = np.asarray(pre, float).copy()

    @classmethod
    def of(cls, return_map: Any, x: np.ndarray) -> Section:
        """The section that a return map's image of ``x`` lies on (its last footfall: the
        transition, time and pre-impact state of :meth:`ReturnMap.last_impact`)."""
        tr, t, pre = return_map.last_impact(x)
        return cls(return_map.k, return_map.p, tr, t, pre)

    # -- pieces of the surface
    def guard(self, y: np.ndarray) -> float:
        """The step guard at a pre-impact state (its units: a height in m for a footfall)."""
        return float(self.k.guards(self.source, self.t, y, self.p)[self.row])

    def reset(self, y: np.ndarray) -> np.ndarray:
        """The post-impact state of a pre-impact state."""
        return self.k.reset(self.tr, self.t, y, self.p)[1]

    def _jac(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        grad = self.k.surface_gradients(self.source, self.t, y, self.p)[0][self.row]
        return grad, self.k.reset_jacobian(self.tr, self.t, y, self.p)[0]

    def tangent(self, y: np.ndarray | None = None) -> np.ndarray:
        """Orthonormal basis (n × d) of the section's tangent space at ``Δ(y)`` (default: at the
        reference): the image under ``DΔ`` of the guard surface's tangent space ``ker ∇g``."""
        grad, D = self._jac(self.pre if y is None else np.asarray(y, float))
        N = np.linalg.svd(grad[None, :])[2][1:].T
        U, s, _ = np.linalg.svd(D @ N, full_matrices=False)
        d = int(np.sum(s > RANK_TOL * s[0])) if s.size and s[0] > 0 else 0
        return U[:, :d]

    def increments(self, S: Sequence[int]) -> np.ndarray | None:
        """``E`` (n × d) of the chart with coordinates ``S`` at the reference: the tangent vector
        of Σ whose coordinates ``S`` are those of a chart increment (``E[S, :] = I``), as
        :func:`chart` gives it for the same ``S``. Any basis ``B`` of the tangent space gives
        ``E = B B[S, :]⁻¹``; ``DΔ`` of a basis of ``ker ∇g`` is one when the reset keeps the
        guard surface's dimension (no SVD), else the orthonormal basis of :meth:`tangent`.
        ``None`` when ``S`` does not chart Σ here (``B[S, :]`` singular, or the wrong number of
        coordinates); entries may be huge or not finite when it charts Σ badly."""
        grad, D = self._jac(self.pre)
        S = np.asarray(S, dtype=int)
        m = int(np.argmax(np.abs(grad)))
        if len(S) == grad.size - 1 and grad[m] != 0.0:
            # e_j − (g_j / g_m) e_m for every j ≠ m: a basis of ker ∇g (coefficients at most 1)
            rest = [j for j in range(grad.size) if j != m]
            B = D[:, rest] - np.outer(D[:, m], grad[rest] / grad[m])
        else:  # the reset collapses directions (or ∇g = 0): an orthonormal basis of its image
            B = self.tangent()
            if B.shape[1] != len(S):
                return None
        try:
            return B @ np.linalg.inv(B[S, :])
        except np.linalg.LinAlgError:
            return None

    @property
    def dimension(self) -> int:
        """``d``, the dimension of the section (the number of section coordinates)."""
        return self.tangent().shape[1]

    def coordinates(self, prefer: Sequence[int] = ()) -> np.ndarray:
        """The section coordinates: ``d`` sorted state indices charting Σ at the reference
        (``prefer`` first, see :func:`chart`)."""
        return chart(self.tangent(), prefer)[0]

    # -- projection
    def project(self, x: np.ndarray, S: Sequence[int] | None = None, *, tol: float = PROJECT_TOL,
                max_iter: int = 30) -> np.ndarray:
        """The state of Σ whose coordinates ``S`` (default :meth:`coordinates`) equal ``x[S]``.

        Newton on ``g(y) = 0, Δ(y)[S] = x[S]`` in the pre-impact state ``y`` from the reference,
        minimum-norm steps (``lstsq``) so that a reset that collapses directions is handled too;
        each step is halved until the residual decreases. Raises :class:`ConvergenceError` when
        no state of Σ near the reference has these coordinates (e.g. a basin cell far from the
        gait) and :class:`StateError` for a state of the wrong length.
        """
        x = np.asarray(x, float)
        n = self.k.meta["nx"][self.target]
        if x.shape != (n,):
            raise StateError(f"project: a state of the section's mode has {n} values, got {x.shape}")
        S = self.coordinates() if S is None else np.asarray(S, dtype=int)
        y = self.pre.copy()

        def residual(y: np.ndarray) -> np.ndarray:
            return np.r_[self.guard(y), self.reset(y)[S] - x[S]]

        goal = tol * max(1.0, float(np.max(np.abs(x[S]), initial=0.0)))
        r = residual(y)
        res = float(np.max(np.abs(r)))
        for _ in range(max_iter):
            if res < goal:
                return self.reset(y)
            grad, D = self._jac(y)
            J = np.vstack([grad[None, :], D[S, :]])
            dy = np.linalg.lstsq(J, -r, rcond=None)[0]
            lam = 1.0
            while lam > 1e-4:
                trial = y + lam * dy
                try:
                    rt = residual(trial)
                except ModelError:  # a singular impulse system far from the reference
                    rt = np.array([np.inf])
                if np.all(np.isfinite(rt)) and float(np.max(np.abs(rt))) < res:
                    break
                lam *= 0.5
            else:
                break
            y, r, res = trial, rt, float(np.max(np.abs(rt)))
        if res < 1e3 * goal:  # stalled at rounding level: as good as this state allows
            return self.reset(y)
        raise ConvergenceError(f"no state on the section has these section coordinates near the reference "
                               f"(residual {res:.3g})")

    def project_many(self, x: np.ndarray, S: Sequence[int], *, tol: float = PROJECT_TOL, max_iter: int = 30,
                     threads: int = 1) -> list[np.ndarray | None]:
        """:meth:`project` of every row of ``x``, the iteration in one compiled call (the GIL
        released, rows shared by ``threads`` threads); ``None`` for a row with no state of Σ
        (where :meth:`project` raises :class:`ConvergenceError`). A row the compiled iteration
        cannot decide (a rank-deficient step, a failing reset) is projected by :meth:`project`."""
        y, off = self.project_array(x, S, tol=tol, max_iter=max_iter, threads=threads)
        return [None if off[r] else y[r].copy() for r in range(len(y))]

    def project_array(self, x: np.ndarray, S: Sequence[int], *, tol: float = PROJECT_TOL, max_iter: int = 30,
                      threads: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`project_many` as one array, rows of NaN where a row has no state of Σ, and the
        mask of those rows: no Python object per row (the cells of a basin map)."""
        x = np.asarray(x, float)
        n = self.k.meta["nx"][self.target]
        if x.ndim != 2 or x.shape[1] != n:
            raise StateError(f"project: states of the section's mode have {n} values, got shape {x.shape}")
        y, ok = self.k.project_batch(self.source, self.tr, self.row, self.t, self.pre, np.asarray(S, int), x, self.p,
                                     tol, max_iter, threads)
        out = y[:, :n].copy()
        off = np.zeros(len(x), dtype=bool)
        for r in np.flatnonzero(~ok).tolist():  # rows the compiled iteration could not decide: the full one
            try:
                out[r] = self.project(x[r], S, tol=tol, max_iter=max_iter)
            except ConvergenceError:
                out[r], off[r] = np.nan, True
        return out, off


__all__ = ["PROJECT_TOL", "RANK_TOL", "Section", "chart"]
