"""Where a step's unknowns sit in a gait's NLP (:func:`~amble.analysis.gait_optimisation.optimize_gait`):
``(X, A, U, T, qe, λ)`` over the ``2N + 1`` points, their bounds, the named groups of bounds,
and the :class:`~amble.analysis.gait_result.Gait` read back from a solution."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..backend.casadi_export import StepFunctions
from ..errors import StateError
from ..modelling.hybrid import HybridSystem
from .gait_result import Gait, bezier_fit


def _bounds(model: Any, fns: StepFunctions, bounds: Mapping | None, N: int, t_guess: float
            ) -> tuple[np.ndarray, np.ndarray]:
    n, d, K = fns.n, fns.dims, 2 * N + 1
    lo_x, hi_x = np.full(2 * n, -np.inf), np.full(2 * n, np.inf)
    limits = dict(getattr(model.tree, "limits", {}) or {}) if getattr(model, "tree", None) is not None else {}
    limits.update(bounds or {})
    for name, (lo, hi) in limits.items():
        if name not in fns.state_names:
            raise StateError(f"bound on {name!r}: not a state variable ({', '.join(fns.state_names)})")
        i = fns.state_names.index(name)
        lo_x[i] = -np.inf if lo is None else lo
        hi_x[i] = np.inf if hi is None else hi
    lim = getattr(model, "input_limits", {}) or {}
    hi_u = np.array([np.inf if lim.get(k) is None else float(lim[k]) for k in fns.input_names])
    T_lo, T_hi = 0.02 * t_guess, 20.0 * t_guess
    lbw = np.concatenate([np.tile(lo_x, K), np.full(n * K, -np.inf), np.tile(-hi_u, K), [T_lo],
                          np.full(n + 2 * d, -np.inf)])
    ubw = np.concatenate([np.tile(hi_x, K), np.full(n * K, np.inf), np.tile(hi_u, K), [T_hi],
                          np.full(n + 2 * d, np.inf)])
    return lbw, ubw


def _bound_groups(fns: StepFunctions, N: int) -> list[tuple[str, int, int]]:
    """Where each kind of bound sits in the vector of unknowns: (name, start, stop)."""
    n, nu, K = fns.n, fns.nu, 2 * N + 1
    s = 2 * n * K + n * K
    return [("joint_limits", 0, 2 * n * K), ("actuator_limits", s, s + nu * K), ("step_time", s + nu * K,
                                                                                   s + nu * K + 1)]


def _gait(system: HybridSystem, model: Any, fns: StepFunctions, pvals: dict, w: np.ndarray, N: int,
          objective: Any, value: float, report: dict, solver: dict, degree: int, alpha: np.ndarray | None = None
          ) -> Gait:
    n, nu, K = fns.n, fns.nu, 2 * N + 1
    X = w[: 2 * n * K].reshape(K, 2 * n)
    A = w[2 * n * K: 3 * n * K].reshape(K, n)
    U = w[3 * n * K: (3 * n + nu) * K].reshape(K, nu)
    T = float(w[(3 * n + nu) * K])
    base = (3 * n + nu) * K + 1
    qe, impulse = w[base: base + n + fns.dims], w[base + n + fns.dims: base + n + 2 * fns.dims]
    # an HZD gait's coefficients (``alpha``, nu × (M+1)) are exported as optimised, not refitted,
    # so the controller holds exactly the polynomial of the collocation
    P = np.array([pvals[k] for k in fns.param_names])
    L = float(fns.distance(X[-1, :n], P))
    forces = np.array([np.asarray(fns.contact(x[:n], x[n:], a, P), float).ravel() for x, a in zip(X, A)])
    return Gait(system=system.name, state_names=list(fns.state_names), input_names=list(fns.input_names),
                params=pvals, objective_name=str(objective), objective=value, fixed_point=X[0].copy(),
                step_time=T, step_length=L, speed=L / T, times=np.linspace(0.0, T, K), states=X,
                accelerations=A, inputs=U, pre_impact_state=X[-1].copy(), impulse=np.asarray(impulse),
                extended_velocity=np.asarray(qe), contact_forces=forces,
                constraints=report, solver=solver, bezier=bezier_fit(model, fns, X, degree, P, alpha))
