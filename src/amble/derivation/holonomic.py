"""Holonomic constraints of a mode, ``φ(q) = 0`` (:meth:`amble.Model.holonomic`): the terms of
the index-1 constrained dynamics

    ``M q̈ = Γ − h + Jᵀλ``,   ``J q̈ = γ``,

with ``J = ∂φ/∂q`` (m × n) and ``γ = −J̇ q̇ = −(∂(J q̇)/∂q) q̇`` — the second time derivative of
``φ`` set to zero (``φ̈ = J q̈ + J̇ q̇``). Baumgarte gains ``(α, β)`` of a set add
``−2α J q̇ − β² φ`` to its rows of ``γ`` (``φ̈ + 2α φ̇ + β² φ = 0``). Nothing is simplified;
code generation shares common subexpressions.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..errors import ModelError
from ..modelling.model import Model


@dataclass(frozen=True)
class Holonomic:
    """The derived terms of a mode's holonomic constraints (sympy, in q, q̇ and parameters)."""

    #: one name per equation, in the order of λ (:attr:`Model.constraint_names`)
    names: list[str]
    #: φ(q), m × 1
    phi: sp.Matrix
    #: ∂φ/∂q, m × n
    J: sp.Matrix
    #: −J̇ q̇ (with the Baumgarte terms where declared), m × 1
    gamma: sp.Matrix


def holonomic_terms(model: Model) -> Holonomic | None:
    """``φ``, ``J`` and ``γ`` of a model's holonomic constraints, or None if it declares none."""
    if not model.holonomic_constraints:
        return None
    q, qd = model.q, sp.Matrix(model.qd)
    phi, gains = [], []
    for name, exprs in model.holonomic_constraints.items():
        phi += exprs
        gains += [model.baumgarte.get(name, (0.0, 0.0))] * len(exprs)
    J = sp.Matrix(len(phi), len(q), lambda i, j: model.diff(phi[i], q[j]))
    v = J * qd  # φ̇
    gamma = sp.zeros(len(phi), 1)
    for i in range(len(phi)):
        acc = sp.Integer(0)
        for j, qj in enumerate(q):
            d = model.diff(v[i], qj)
            if d != 0:
                acc += d * qd[j]
        alpha, beta = gains[i]
        gamma[i] = -acc - (2 * sp.Float(alpha) * v[i] if alpha else 0) - (sp.Float(beta) ** 2 * phi[i] if beta else 0)
    return Holonomic(names=model.constraint_names, phi=sp.Matrix(phi), J=J, gamma=gamma)


def refuse_constrained(model: Model, what: str) -> None:
    """A :class:`ModelError` naming the mode if it has holonomic constraints: ``what`` (a
    computation written for ``M q̈ + h = Γ`` alone) would ignore them and give wrong numbers."""
    if model.holonomic_constraints:
        raise ModelError(f"mode {model.name!r} has holonomic constraints ({', '.join(model.holonomic_constraints)}): "
                         f"{what} does not take them into account")
