"""Exact linearisation of a mode's open-loop dynamics about a state and an input (for LQR).

With ``x = (q, q̇)`` and ``ẋ = f(x, u) = (q̇, q̈)``, ``q̈ = M⁻¹ (Γ + B u − h)``, the Jacobians are
assembled from the derived symbolic derivatives of ``M``, ``h``, ``Γ`` and ``B`` — no finite
differences:

    ∂q̈/∂q_k = M⁻¹ (∂(Γ + B u − h)/∂q_k − ∂M/∂q_k · q̈),    ∂q̈/∂q̇_k = M⁻¹ ∂(Γ − h)/∂q̇_k,
    ∂q̈/∂u = M⁻¹ B,

so ``A = [[0, I], [∂q̈/∂q, ∂q̈/∂q̇]]`` and ``B_x = [[0], [M⁻¹ B]]``. ``Γ`` is the passive force:
the model's own control law is left out (``u`` is the input one linearises about).
"""

from __future__ import annotations

import weakref
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from ..derivation.equations import derive
from ..derivation.holonomic import refuse_constrained
from ..errors import StateError
from ..modelling.geometry import t as _t
from ..modelling.hybrid import HybridSystem

_FN: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _functions(model: Any) -> Any:
    hit = _FN.get(model)
    if hit is None:
        refuse_constrained(model, "linearize")
        eq = derive(model)
        q, qd = model.q, model.qd
        us = list(eq.inputs)
        r = eq.Gamma - eq.h + (eq.B * sp.Matrix(us) if us else sp.zeros(len(q), 1))
        dM = [model.jacobian(eq.M[:, j]) for j in range(len(q))]  # ∂M[:, j]/∂q, n × n each
        args = [_t, *q, *qd, *us, *model.params]
        hit = sp.lambdify(args, [eq.M, r, r.jacobian(q), r.jacobian(qd), eq.B, dM], "numpy", cse=True)
        _FN[model] = hit
    return hit


def linearize(system: HybridSystem, x: Sequence[float], u: Sequence[float] | None = None, *,
              mode: str | None = None, t: float = 0.0, params: Mapping[str, float] | None = None
              ) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` of ``ẋ ≈ f(x₀, u₀) + A δx + B δu`` for one mode (default: the first) at state
    ``x`` (coordinates then velocities) and input ``u`` (declaration order; default zero)."""
    mode = mode or system.mode_names[0]
    if mode not in system.modes:
        raise StateError(f"system {system.name!r} has no mode {mode!r}")
    model = system.modes[mode]
    n, nu = len(model.q), len(model.inputs)
    x = np.asarray(x, float).ravel()
    if x.size != 2 * n or not np.all(np.isfinite(x)):
        raise StateError(f"linearize: mode {mode!r} needs a finite state of {2 * n} values, got {x.tolist()}")
    u = np.zeros(nu) if u is None else np.asarray(u, float).ravel()
    if u.size != nu or not np.all(np.isfinite(u)):
        raise StateError(f"linearize: mode {mode!r} has {nu} input(s), got {u.tolist()}")
    pv = dict(system.parameters)
    pv.update(params or {})
    M, r, rq, rv, B, dM = _functions(model)(t, *x, *u, *[pv[str(s)] for s in model.params])
    M, r, rq, rv = (np.asarray(a, float) for a in (M, r, rq, rv))
    qdd = np.linalg.solve(M, r.ravel())
    dMq = np.stack([np.asarray(d, float) for d in dM], axis=1)  # [i, j, k] = ∂M_ij/∂q_k
    A_q = np.linalg.solve(M, rq - np.einsum("ijk,j->ik", dMq, qdd))
    A_v = np.linalg.solve(M, rv)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [A_q, A_v]])
    Bu = np.linalg.solve(M, np.asarray(B, float).reshape(n, nu)) if nu else np.zeros((n, 0))
    Bx = np.vstack([np.zeros((n, nu)), Bu])
    return A, Bx
