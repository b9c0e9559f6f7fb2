"""Unilateral contact with restitution, and the resting mode it settles into.

A contact is a gap function ``φ(q, t)`` (m; ``φ > 0`` apart, ``φ = 0`` touching) of a mode, and a
restitution coefficient ``e`` (``0 ≤ e ≤ 1``; an expression, usually a parameter). With
``J = ∂φ/∂q`` and the normal velocity ``φ̇ = J q̇ + ∂φ/∂t``:

* **Impact** (``φ`` reaches zero falling): the impulse along ``Jᵀ`` that turns ``φ̇⁻`` into
  ``φ̇⁺ = −e φ̇⁻``, ``q̇⁺ = q̇⁻ − (1 + e) w φ̇⁻ / (J w)`` with ``w = M⁻¹ Jᵀ`` (Newton's law of
  restitution; ``M`` the mass matrix).
* **Rest** (a Zeno cluster of impacts, or ``e = 0``): the same impulse with ``e = 0`` (``φ̇⁺ = 0``),
  then the *resting mode*: the model with the constraint ``φ = 0`` held by a Lagrange
  multiplier ``λ`` (N, the contact force), added as the generalized force ``Jᵀ λ``. ``λ`` follows
  from ``M q̈ + h = Γ + Jᵀ λ`` and ``φ̈ = J q̈ + b = 0`` (``b``: the part of ``φ̈`` without ``q̈``):
  ``λ = −(wᵀ (Γ − h) + b) / (J w)``.
* **Lift-off**: when ``λ`` falls through zero (the contact would have to pull), back to the free
  mode with the state unchanged.

The contact force is derived symbolically (one solve with ``M``), which suits models of a few
coordinates. Other transitions of the free mode are not carried into the resting mode.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from ..errors import ModelError
from ..modelling.geometry import t
from ..modelling.hybrid import Explicit, HybridSystem, Transition
from ..modelling.model import Model
from ..modelling.text import expr_of
from .equations import derive
from .holonomic import refuse_constrained


def contact_force(model: Model, gap: Any) -> sp.Expr:
    """The multiplier ``λ(q, q̇, t)`` (N per unit of ``∂φ/∂q``; N for a gap in metres along a
    unit normal) that holds ``φ(q, t) = 0`` on ``model`` (see the module docstring)."""
    refuse_constrained(model, "contact_force")
    eq = derive(model)
    J, w = _jacobian_and_w(model, gap)
    phid = _normal_velocity(model, gap)
    # b: φ̈ with q̈ = 0, i.e. the derivative of φ̇(q, q̇, t) along q̇ (q fixed) and t
    b = sum((sp.diff(phid, qi) * qdi for qi, qdi in zip(model.q, model.qd)), sp.Integer(0)) + sp.diff(phid, t)
    free = eq.closed_loop_force - eq.h
    lam = -((w.T * free)[0, 0] + b) / (J * w)[0, 0]
    return sp.cancel(lam) if len(model.q) <= 3 else lam


def holonomic_forces(model: Model) -> dict[str, sp.Expr]:
    """``λ(q, q̇, t)`` of each equation of a mode's holonomic constraints (:meth:`Model.holonomic`),
    by name (:attr:`Model.constraint_names`), as expressions: with ``W = M⁻¹Jᵀ``,
    ``λ = (J W)⁻¹ (γ − Wᵀ (Γ − h))`` — the values ``Kernels.constraint_forces`` computes, written
    out so that a guard can use them (a foot lifts off when its normal force falls through zero).
    Two symbolic solves (with ``M``, then with ``J W``): for models of a few coordinates."""
    eq = derive(model)
    hol = eq.holonomic
    if hol is None:
        raise ModelError(f"model {model.name!r} declares no holonomic constraints")
    W = eq.M.LUsolve(hol.J.T)
    lam = (hol.J * W).LUsolve(hol.gamma - W.T * (eq.closed_loop_force - eq.h))
    return dict(zip(hol.names, lam))


def _jacobian_and_w(model: Model, gap: Any) -> tuple[sp.Matrix, sp.Matrix]:
    eq = derive(model)
    J = sp.Matrix([[sp.diff(gap, qi) for qi in model.q]])
    w = eq.M.LUsolve(J.T)
    return J, w


def _normal_velocity(model: Model, gap: Any) -> sp.Expr:
    return sum((sp.diff(gap, qi) * qdi for qi, qdi in zip(model.q, model.qd)), sp.Integer(0)) + sp.diff(gap, t)


def restitution_velocities(model: Model, gap: Any, restitution: Any) -> list[sp.Expr]:
    """``q̇⁺`` of an impact with restitution ``e`` on the gap ``φ`` (see the module docstring)."""
    J, w = _jacobian_and_w(model, gap)
    phid = _normal_velocity(model, gap)
    jw = (J * w)[0, 0]
    return [qdi - (1 + restitution) * w[i, 0] * phid / jw for i, qdi in enumerate(model.qd)]


def unilateral_contact(system: HybridSystem, name: str, mode: str, gap: Any, restitution: Any,
                       rest_mode: str | None = None) -> tuple[Transition, Transition, Transition]:
    """Declare a unilateral contact ``gap(q, t) ≥ 0`` of ``mode`` with restitution ``restitution``,
    and the resting mode it settles into (named ``rest_mode``, default ``<mode>_<name>``).

    Adds the mode and three transitions (:meth:`HybridSystem.resting_contact`): ``name`` (the
    impact), ``<name>_rest`` (into the resting mode when impacts accumulate, or at once with
    ``e = 0``) and ``<name>_liftoff`` (when the contact force would turn negative). The contact
    force in the resting mode is :func:`contact_force`; a trajectory's rows in that mode can
    be evaluated with ``contact_force(...)`` through :func:`sympy.lambdify`. Returns the three
    transitions.
    """
    system._check_mode(mode)
    model = system.modes[mode]
    if model.tree is not None:
        raise ModelError(f"model {model.name!r}: a unilateral contact on a rigid-body tree is not supported")
    gap = expr_of(gap, model.symbol_table(), what=f"model {model.name!r}: contact gap")
    if not (gap.free_symbols & set(model.q)):
        raise ModelError(f"contact {name!r}: the gap {gap} does not depend on the coordinates of mode {mode!r}")
    if gap.free_symbols & set(model.qd):
        raise ModelError(f"contact {name!r}: the gap {gap} must be a function of the coordinates and time only")
    e = expr_of(restitution, model.symbol_table(), what=f"contact {name!r}: restitution")
    if e.is_number and not (0 <= float(e) <= 1):
        raise ModelError(f"contact {name!r}: restitution must be in [0, 1], got {e}")
    rest_name = rest_mode or f"{mode}_{name}"
    lam = contact_force(model, gap)
    J = sp.Matrix([[sp.diff(gap, qi) for qi in model.q]])
    rest = model.constrained(rest_name, {})  # the same model, plus the contact force below
    rest.force(J.T * lam)
    system.add_mode(rest_name, rest)
    same = list(model.q)
    bounce = Explicit(q=same, qd=restitution_velocities(model, gap, e))
    settle = Explicit(q=same, qd=restitution_velocities(model, gap, sp.Integer(0)))
    leave = Explicit(q=same, qd=list(model.qd))
    return system.resting_contact(name, mode, rest_name, gap, bounce, settle, lam, leave)
