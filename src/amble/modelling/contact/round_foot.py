"""Round feet: rolling without slip on a slope, and the material contact point of an impact.

A planar foot is an arc of radius ``r`` about a centre ``C`` fixed on its leg; the leg turns
with the body angle ``θ`` (rad, from the vertical, positive leaning downhill, the convention
of :func:`~amble.modelling.geometry.R`). The ground is the plane through the origin with unit
normal ``n = (sin γ, cos γ)`` and downhill direction ``d = (cos γ, −sin γ)`` (see
:mod:`.ground`). While the arc touches the ground its contact is the lowest point of the arc,
``C − r n``.

**Rolling without slip.** The contact advances by ``r Δθ`` along the slope as the foot turns by
``Δθ``. With the reference of this module — the contact is at the origin when the foot's axis
is along the slope normal, ``θ = γ`` — the centre of a rolling stance foot is (metres)::

    C(θ) = r (θ − γ) d + r n                                  (rolling_centre)

so that the material point of the foot at the contact has zero velocity,
``Ċ + ω × (−r n) = r θ̇ d − r θ̇ d = 0``.

**Impact of a round foot.** A plastic, non-sliding impact constrains the velocity of the
*material* point of the foot at the contact, ``v = Ċ + ω × (−r n) = Ċ − r θ̇ d`` (2D, ``ω = θ̇``
about the axis normal to the plane), not the velocity of the geometric lowest point ``C − r n``
(which moves with ``Ċ`` only: a rolling wheel's lowest point moves with its hub). This ``v`` is
the velocity of the *rolling point*::

    Q = C − r n − r (θ − γ) d                                 (RoundFoot.rolling)

the ground point where the foot's axis would touch if the foot rolled upright from its current
contact (``Q̇ = Ċ − r θ̇ d`` identically). An :class:`~amble.modelling.hybrid.Impact` of ``Q``
therefore imposes exactly the material-point constraint, and ``Q`` is also where the next
step's frame puts its origin: with the new stance foot at ``rolling_centre`` the positions
carry over unchanged through the impact. The stance foot's own rolling point is the origin at
all times.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import sympy as sp

from ...errors import ModelError
from ..model import Model
from .ground import slope_downhill, slope_normal


@dataclass(frozen=True)
class RoundFoot:
    """The named points of a round foot of radius ``radius`` (m), declared by :func:`round_foot`:
    ``centre`` (the arc's centre, on the leg), ``contact`` (the arc's lowest point ``C − r n``,
    where it touches the slope) and ``rolling`` (the point whose velocity is that of the material
    point at the contact, the constrained point of an impact; see the module docstring)."""

    centre: str
    contact: str
    rolling: str
    radius: Any


def rolling_centre(angle: Any, radius: Any, slope: Any) -> sp.Matrix:
    """Position (m) of the arc centre of a stance foot of radius ``radius`` rolling without slip
    on the slope: ``r (θ − γ) d + r n``, the contact being at the origin when the body angle
    ``angle`` equals ``slope`` (the foot's axis along the slope normal)."""
    return radius * (angle - slope) * slope_downhill(slope) + radius * slope_normal(slope)


def round_foot(model: Model, name: str, centre: Any, angle: Any, radius: Any, slope: Any,
               link: str | None = None) -> RoundFoot:
    """Declare a round foot of ``model`` (planar): the arc centre at ``centre`` (a position, e.g.
    ``hip − l R(θ)`` for a swing foot or :func:`rolling_centre` for a stance foot) on a body
    turning with ``angle``, radius ``radius`` (m) on the slope of angle ``slope``.

    Names the points ``name`` (the contact ``C − r n``), ``name_centre`` (linked to ``link``
    when given, for drawing) and ``name_rolling`` (see the module docstring), and returns them
    as a :class:`RoundFoot` for :func:`~amble.modelling.contact.footfall.heel_strike` and
    :func:`~amble.modelling.walker.walker`.
    """
    if model.dims != 2:
        raise ModelError(f"model {model.name!r}: round_foot is planar; a {model.dims}D model needs "
                         "the contact of a surface, not of an arc")
    n, d = slope_normal(slope), slope_downhill(slope)
    c = model.point(f"{name}_centre", centre, link=link)
    model.point(name, c - radius * n, link=f"{name}_centre")
    model.point(f"{name}_rolling", c - radius * n - radius * (angle - slope) * d)
    return RoundFoot(centre=f"{name}_centre", contact=name, rolling=f"{name}_rolling", radius=radius)
