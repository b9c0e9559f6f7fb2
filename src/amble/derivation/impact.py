"""Impulsive reset maps: the post-impact velocity of a plastic impact or a joint lock.

An impulsive reset is the linear system (thesis, floating-base impact model)

* ``M_e (q̇e⁺ − q̇e⁻) = Jᵀ λ``   (the impulse ``λ`` changes the momentum along the constraint),
* ``J q̇e⁺ = 0``                (after the event the constraint holds: plastic, no sliding),

solved at run time for ``(q̇e⁺, λ)`` (``amble_impulse`` in ``backend/_c/amble_core.h``). This
module derives its symbolic ingredients:

* **Impact** of a point with the ground: the model is extended by its base (stance-foot)
  position ``b`` (``dims`` coordinates, every point shifted by ``b``), because the old stance
  foot may lift off. With ``Jᵢ = ∂rᵢ/∂q``, ``S = Σ mᵢ Jᵢᵀ`` and total mass ``mₜ``,
  ``M_e = [[M, S], [Sᵀ, mₜ I]]``, and the impacting point has ``J = [J_c, I]``. Before the
  impact the base is at rest: ``q̇e⁻ = (q̇⁻, 0)``.
* **Lock** ``c(q) = 0`` (e.g. a knee): no extension, ``M_e = M`` and ``J = ∂c/∂q``.

For a rigid-body tree the blocks ``S``, ``mₜ`` and ``J`` come from the tree's recursion
(:mod:`amble.derivation.tree_impact`), not from the sum over its bodies; only point masses placed
outside the tree's bodies are summed.

Then the coordinates are relabelled for the target mode, ``q_new = r(q)``, and velocities follow
by the chain rule: ``q̇_new = (∂r/∂q) q̇⁺`` — :attr:`ImpulseData.velocity_map` is ``∂r/∂q``
(only the first ``n`` entries of ``q̇e⁺`` are used; the base velocity is dropped).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from ..errors import ModelError
from ..modelling.hybrid import Impact, Lock, Reset, ResetVisitor, target_exprs
from ..modelling.model import Model
from ..modelling.tree import RigidTree
from .equations import Equations
from .tree_impact import tree_impact_terms


@dataclass(frozen=True)
class ImpulseData:
    """Symbolic impulsive reset of one transition (expressions in the source q and parameters).

    ``Me``: (extended) mass matrix, ``ne × ne``; ``Jc``: constraint Jacobian, ``nc × ne``;
    ``q_new``: target coordinates as expressions of the source coordinates; ``velocity_map``:
    ``∂q_new/∂q``, ``nd × n``; ``defs``: the named intermediate quantities ``(symbol,
    definition)`` that ``Me`` and ``Jc`` use, in order (a tree model's, when asked for in compact
    form; empty otherwise).
    """

    Me: sp.Matrix
    Jc: sp.Matrix
    q_new: list[sp.Expr]
    velocity_map: sp.Matrix
    defs: Sequence[tuple[sp.Symbol, sp.Expr]] = ()


def extended_impact_data(model: Model, equations: Equations, point: str,
                         compact: bool = False) -> tuple[sp.Matrix, sp.Matrix]:
    """Mass matrix ``M_e`` and contact Jacobian ``J`` of the model extended with its base position
    (see the module docstring), for a plastic impact of ``point``. ``compact``: a tree's blocks
    stay in its named intermediate quantities (``equations.M`` should then be the compact ``M``)."""
    if model._k_override is not None or model._l_override is not None:
        raise ModelError(
            f"model {model.name!r}: an Impact reset needs the kinetic energy from point masses "
            "(K or L was given outright); give an Explicit reset instead"
        )
    if model._k_added:
        # ½ m_H |ṗ_hip|² and ½ m_H l² θ̇² are the same expression in q̇, but only the first carries
        # linear momentum into the impact: the expression cannot tell which it is.
        raise ModelError(
            f"model {model.name!r}: an Impact reset cannot use kinetic terms added with add_kinetic "
            f"({len(model._k_added)} term(s)): from the expression alone it cannot tell whether a term is "
            "a translating mass (whose momentum the impact changes) or rotational inertia; declare "
            "masses with point(..., mass=...) and rotational inertia with inertia() or body_inertia(), "
            "or give an Explicit reset"
        )
    # Rotational inertia (inertia(), body_inertia()) does not depend on the base translation, so
    # it stays in the q-block M and contributes nothing to the base blocks.
    n, d = len(model.q), model.dims
    S = sp.zeros(n, d)
    mt = sp.Integer(0)
    tree = model.tree if isinstance(model.tree, RigidTree) and point in model.tree.point_frames else None
    Jp = None
    if tree is not None:
        ST, mt, Jp = tree_impact_terms(tree, point)
        if not compact:
            ST, mt, Jp = tree.defs.expand(ST), tree.defs.expand(mt), tree.defs.expand(Jp)
        S = ST.T
    for name, m in model.masses.items():
        if tree is not None and name in tree.com_points:
            continue  # the tree's bodies (as in its M)
        J = model.jacobian(model.points[name])
        S += m * J.T
        mt += m
    Me = sp.zeros(n + d, n + d)
    Me[:n, :n] = equations.M
    Me[:n, n:] = S
    Me[n:, :n] = S.T
    Me[n:, n:] = mt * sp.eye(d)
    Jc = sp.zeros(d, n + d)
    Jc[:, :n] = Jp if Jp is not None else model.jacobian(model.points[point])
    Jc[:, n:] = sp.eye(d)
    return Me, Jc


def lock_jacobian(model: Model, constraint: sp.Expr) -> sp.Matrix:
    """``∂c/∂q`` of a lock constraint ``c(q) = 0``, as a ``1 × n`` matrix."""
    c = sp.sympify(constraint)
    return sp.Matrix([[sp.diff(c, qi) for qi in model.q]])


class _ImpulseMatrices(ResetVisitor[tuple[sp.Matrix, sp.Matrix]]):
    """``(Me, Jc)`` of an impulsive reset: the (extended) mass matrix and the Jacobian of what
    the impulse enforces (the impacting point's velocity, or the lock constraint's rate)."""

    def __init__(self, model: Model, equations: Equations, compact: bool, what: str) -> None:
        self.model, self.equations, self.compact = model, equations, compact
        self.what = f"{what}: not an impulsive reset (Impact or Lock)"

    def impact(self, reset: Impact) -> tuple[sp.Matrix, sp.Matrix]:
        return extended_impact_data(self.model, self.equations, reset.point, self.compact)

    def lock(self, reset: Lock) -> tuple[sp.Matrix, sp.Matrix]:
        return self.equations.M, lock_jacobian(self.model, reset.constraint)


def impulse_data(model: Model, equations: Equations, reset: Reset, target_model: Model,
                 what: str = "reset", compact: bool = False) -> ImpulseData:
    """The impulsive reset of an :class:`~amble.modelling.hybrid.Impact` or
    :class:`~amble.modelling.hybrid.Lock` from ``model`` (with its derived ``equations``) into
    ``target_model``; ``what`` names the transition in error messages. ``compact``: ``Me`` and
    ``Jc`` of a tree model in its named intermediate quantities, listed in
    :attr:`ImpulseData.defs` (``equations.M`` is then the compact ``M``, as code generation has it)."""
    Me, Jc = reset.accept(_ImpulseMatrices(model, equations, compact, what))
    q_new = target_exprs(target_model, reset.relabel, what, source=model)
    # model.jacobian: a tree's relabelling (the new base's angles from a foot's rotation) is a
    # shared graph, differentiated once per shared part
    velocity_map = model.jacobian(sp.Matrix(q_new)) if q_new else sp.zeros(0, len(model.q))
    defs = model.tree.defs.needed([*Me, *Jc]) if compact and model.tree is not None else []
    return ImpulseData(Me=Me, Jc=Jc, q_new=q_new, velocity_map=velocity_map, defs=defs)
