"""Compliant ground: a point that sinks into the ground meets a nonlinear spring and damper.

Instead of an impact (a velocity jump) the ground pushes back with a force of the penetration
``δ = −n·p`` (m, ``δ > 0`` below the ground; ``n`` its normal, :mod:`.ground`) and its rate
``δ̇``, the law of Hunt & Crossley (1975)::

    F = k δ^a (1 + d δ̇) n        while δ > 0 and 1 + d δ̇ > 0, else 0

``k`` the stiffness (N/m^a), ``a`` the exponent (3/2: Hertz's law of a sphere on a plane; 1: a
linear spring whose damping grows with the penetration), ``d`` the dissipation (s/m). The force
is continuous where contact begins (``δ = 0``) and the ground never pulls (the force is cut at
zero when the damping term would reverse it), so a bounce ends where the force reaches zero.
With ``d = 0`` the contact is elastic: the point leaves with the speed it came with. The
switches ``δ = 0`` and ``1 + d δ̇ = 0`` are located like every kink of a force
(:mod:`amble.derivation.switching`), so no step straddles the start or end of a contact.

The force acts at the point along the normal only (no friction): a point resting on compliant
ground sinks to where ``k δ^a`` carries its weight.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from ...errors import ModelError
from ..geometry import t
from ..model import Model
from ..text import expr_of
from .ground import height_above_slope, slope_normal

#: Hertz's exponent of a sphere pressed into a plane
HERTZ = sp.Rational(3, 2)


def compliant_contact(model: Model, point: str, stiffness: Any, dissipation: Any = 0, slope: Any = 0,
                      exponent: Any = HERTZ) -> sp.Expr:
    """Add the Hunt–Crossley force of the ground (module docstring) on ``point`` of ``model`` and
    return its normal component ``F`` (N, ``≥ 0``) as an expression of the state.

    ``stiffness`` ``k`` (N/m^a), ``dissipation`` ``d`` (s/m), ``exponent`` ``a`` (≥ 1) and the
    ground's ``slope`` (rad) may be numbers, parameters or expressions of them.
    """
    if point not in model.points:
        raise ModelError(f"model {model.name!r}: compliant contact on unknown point {point!r}")
    table = model.symbol_table()
    what = f"model {model.name!r}: compliant contact of {point!r}"
    k = expr_of(stiffness, table, what=f"{what}: stiffness")
    d = expr_of(dissipation, table, what=f"{what}: dissipation")
    a = expr_of(exponent, table, what=f"{what}: exponent")
    slope = expr_of(slope, table, what=f"{what}: slope")
    checks = (("stiffness", k, lambda v: v > 0, "positive"), ("dissipation", d, lambda v: v >= 0, "≥ 0"),
              ("exponent", a, lambda v: v >= 1, "≥ 1"))
    for name, value, ok, need in checks:
        if value.is_number and not ok(float(value)):
            raise ModelError(f"{what}: {name} must be {need}, got {value}")
    depth = -height_above_slope(model, point, slope)
    rate = sum((sp.diff(depth, qi) * qdi for qi, qdi in zip(model.q, model.qd)), sp.diff(depth, t))
    # |δ|^a, not δ^a: the branch is taken only where δ > 0, but generated code may evaluate a
    # shared power on both sides of the switch, and a negative base to a fractional power is NaN
    push = k * sp.Abs(depth) ** a * (1 + d * rate)
    force = sp.Piecewise((push, sp.And(depth > 0, 1 + d * rate > 0)), (0, True))
    model.point_force(point, force * slope_normal(slope, model.dims))
    return force
