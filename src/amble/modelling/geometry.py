"""Vector helpers for writing positions: the thesis' rotation vectors and column vectors, and the
time symbol ``t``.

Angles in radians, from the vertical, positive leaning in the walking direction (+x).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import sympy as sp

from .text import expr_of

#: The time symbol, for explicitly time-dependent forces Γ(q, q̇, t).
t = sp.Symbol("t", real=True)


def R(theta: sp.Expr) -> sp.Matrix:
    """2D unit vector at angle ``theta`` from the vertical, clockwise positive (thesis Eq. 6).

    Returns ``(sin θ, cos θ)`` as an ``(x, z)`` column: the direction from a foot to the hip
    of a leg leaning forward by ``theta``.
    """
    return sp.Matrix([sp.sin(theta), sp.cos(theta)])


def R3(theta: sp.Expr, phi: sp.Expr) -> sp.Matrix:
    """3D unit vector of thesis Eq. 37: ``(sin Θ cos Φ, sin Φ, cos Θ cos Φ)`` in ``(x, y, z)``.

    ``Θ`` tilts the vector forward (sagittal plane), ``Φ`` sideways (coronal plane, towards +y).
    """
    return sp.Matrix([sp.sin(theta) * sp.cos(phi), sp.sin(phi), sp.cos(theta) * sp.cos(phi)])


def Rx(angle: sp.Expr) -> sp.Matrix:
    """Rotation by ``angle`` (rad, right-handed) about the x axis, as a 3 × 3 matrix."""
    c, s_ = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[1, 0, 0], [0, c, -s_], [0, s_, c]])


def Ry(angle: sp.Expr) -> sp.Matrix:
    """Rotation by ``angle`` (rad, right-handed) about the y axis, as a 3 × 3 matrix."""
    c, s_ = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[c, 0, s_], [0, 1, 0], [-s_, 0, c]])


def Rz(angle: sp.Expr) -> sp.Matrix:
    """Rotation by ``angle`` (rad, right-handed) about the z axis, as a 3 × 3 matrix."""
    c, s_ = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[c, -s_, 0], [s_, c, 0], [0, 0, 1]])


def vector(*components: Any) -> sp.Matrix:
    """A column vector from components (numbers or sympy expressions)."""
    if len(components) == 1 and isinstance(components[0], Iterable):
        components = tuple(components[0])
    return sp.Matrix([expr_of(c, what="vector component") for c in components])
