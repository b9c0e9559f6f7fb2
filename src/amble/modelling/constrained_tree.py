"""A rigid-body tree with some joint coordinates tied to the others: ``Model.constrained()`` of
a tree model (e.g. a locked knee, ``{knee: 0}``, or a coupled pair, ``{b: a}``).

The bodies and joints stay those of the source tree; its positions, velocities, energies and
named intermediate quantities are carried over with each eliminated coordinate ``q_k`` replaced
by its expression ``φ_k(q)`` and its rate by ``φ̇_k = (∂φ_k/∂q) q̇``. The equations of motion
follow by projection (:func:`amble.derivation.tree.tree_dynamics`): with ``J = ∂q_full/∂q``,
``M = Jᵀ M_full J`` and ``h = Jᵀ (h_full + M_full J̇ q̇)`` — the source tree's recursion, not a
second derivation.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from .dag import dag_subs
from .defs import Defs


class ConstrainedTree:
    """The tree of a constrained model (``model.tree`` of ``Model.constrained()``'s result)."""

    def __init__(self, source: Any, model: Any, substitutions: dict[sp.Symbol, sp.Expr]) -> None:
        #: the tree of the model that was constrained (a ``RigidTree`` or another ``ConstrainedTree``)
        self.source = source
        self.model = model
        #: q_k → φ_k(q) and q̇_k → φ̇_k(q, q̇) of the eliminated coordinates
        self.substitutions = dict(substitutions)
        self._memo: dict = {}
        self._defs: Defs | None = None
        self.com_points = source.com_points
        kept = {str(s) for s in model.q}
        self.limits = {k: v for k, v in source.limits.items() if k in kept}
        self.point_velocities = {n: self.replace(v) for n, v in source.point_velocities.items()}

    def replace(self, expr: Any) -> Any:
        """An expression of the source model in this model's coordinates (shared parts once)."""
        return dag_subs(expr, self.substitutions, self._memo)

    def kinetic(self) -> sp.Expr:
        return self.replace(self.source.kinetic())

    def potential(self, gravity: sp.Matrix) -> sp.Expr:
        return self.replace(self.source.potential(gravity))

    @property
    def defs(self) -> Defs:
        """The source tree's named intermediate quantities, substituted (see :meth:`sync`)."""
        return self._defs if self._defs is not None else self.sync()

    def sync(self) -> Defs:
        """Take over the source's definitions as they are now (its dynamics add some)."""
        self._defs = self.source.defs.substituted(self.substitutions)
        return self._defs

    def jacobian(self) -> tuple[sp.Matrix, sp.Matrix]:
        """``J = ∂q_full/∂q`` (source coordinates × these) and ``J̇ q̇``."""
        full = sp.Matrix([self.substitutions.get(qi, qi) for qi in self.source.model.q])
        q, qd = sp.Matrix(self.model.q), sp.Matrix(self.model.qd)
        J = full.jacobian(q)
        return J, (J * qd).jacobian(q) * qd
