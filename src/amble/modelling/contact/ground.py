"""The ground of a walker: a plane through the stance foot, descending along ``+x`` at ``slope``.

Every step's frame has its origin at the stance foot's contact. The ground's unit normal is
``n = (sin γ, cos γ)`` in 2D (``(sin γ, 0, cos γ)`` in 3D) and its downhill direction is
``d = (cos γ, −sin γ)`` (``(cos γ, 0, −sin γ)``), with ``γ`` the slope (rad, positive descending
along ``+x``). A point's height above the ground is ``n·p``; it is ahead of the stance foot
when ``d·p > 0``. Angles, lengths and the signs of every contact law in this package follow it.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from ..model import Model


def _in_plane(dims: int, a: Any, b: Any) -> sp.Matrix:
    """The vector with ``x = a`` and vertical ``b`` in a model of ``dims`` dimensions."""
    return sp.Matrix([a, b]) if dims == 2 else sp.Matrix([a, 0, b])


def slope_normal(slope: Any, dims: int = 2) -> sp.Matrix:
    """Unit normal ``n`` of the slope (see the module docstring), ``dims`` components."""
    return _in_plane(dims, sp.sin(slope), sp.cos(slope))


def slope_downhill(slope: Any, dims: int = 2) -> sp.Matrix:
    """Unit vector ``d`` along the slope, pointing downhill (see the module docstring)."""
    return _in_plane(dims, sp.cos(slope), -sp.sin(slope))


def height_above_slope(model: Model, point: str, slope: Any) -> sp.Expr:
    """Height (m) of a named point above the slope plane through the origin, along its normal."""
    return (slope_normal(slope, model.dims).T * model.points[point])[0, 0]


def distance_along_slope(model: Model, point: str, slope: Any) -> sp.Expr:
    """Distance (m) of a named point ahead of the origin, measured downhill along the slope."""
    return (slope_downhill(slope, model.dims).T * model.points[point])[0, 0]
