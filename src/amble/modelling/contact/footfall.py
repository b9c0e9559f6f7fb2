"""A footfall: a foot reaches the ground ahead of the stance foot and strikes it plastically.

The foot is a point (a point foot) or a :class:`~.round_foot.RoundFoot`. The guard is the foot's
height above the ground (:mod:`.ground`) falling through zero, enabled only while the foot is
ahead of the stance foot; the reset is a derived plastic, non-sliding impact of the foot's
material point (:class:`~amble.modelling.transitions.Impact`, whose impulse
:mod:`amble.derivation.impact` derives), followed by the relabelling of the legs.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import sympy as sp

from ..expressions import checked_expr
from ..model import Model
from ..transitions import Guard, Impact
from .ground import distance_along_slope, height_above_slope
from .round_foot import RoundFoot

#: A footfall needs the foot ahead of the stance foot by this fraction of the model's size.
STEP_MARGIN = 1e-6


def model_size(model: Model) -> sp.Expr:
    """A length of the model in its current configuration: the root mean square distance of its
    named points from the origin (the stance foot) — the scale of an enabling margin."""
    pts = list(model.points.values())
    if not pts:
        return sp.Integer(1)
    return sp.sqrt(sum(((p.T * p)[0, 0] for p in pts), sp.Integer(0)) / len(pts))


def _contact_point(foot: str | RoundFoot) -> str:
    return foot.contact if isinstance(foot, RoundFoot) else foot


def heel_strike(model: Model, foot: str | RoundFoot, slope: Any, relabel: Mapping[Any, Any],
                margin: Any = None, stance: str | RoundFoot | None = None,
                step_height: Any = 0) -> tuple[Guard, Impact]:
    """Guard and reset of a footfall: ``foot`` reaches the slope while ahead of the stance foot
    by more than ``margin`` (default :data:`STEP_MARGIN` × :func:`model_size`, so that legs
    passing each other — the foot at the stance foot up to round-off — are no footfall),
    followed by a plastic impact and the leg relabelling.

    ``foot`` is a point (a point foot) or a :class:`~.round_foot.RoundFoot`: then its contact
    point meets the slope and the impact constrains the material point of the foot at the
    contact (its ``rolling`` point, which also becomes the next step's origin). ``stance``
    names the stance foot's contact (a point or a ``RoundFoot``) that the foot must be ahead
    of; by default the origin, where a point stance foot stands. ``step_height`` (m, along the
    slope's normal): the ground the foot meets lies this far above the stance foot's slope plane
    — a step up if positive, down if negative; with a parameter, one step's terrain disturbance
    (the next step's ground is again the plane through the new stance foot).
    """
    contact = _contact_point(foot)
    if margin is None:
        margin = STEP_MARGIN * model_size(model)
    ahead = distance_along_slope(model, contact, slope)
    if stance is not None:
        ahead -= distance_along_slope(model, _contact_point(stance), slope)
    # unevaluated: deciding ``ahead > margin`` asks sympy for signs of the whole expression, which
    # for a rigid-body tree's positions (shared graphs) takes minutes; the compiled code decides it
    height = height_above_slope(model, contact, slope) - checked_expr(model, step_height, "step height")
    guard = Guard(height, -1, sp.StrictGreaterThan(ahead, margin, evaluate=False))
    return guard, Impact(foot.rolling if isinstance(foot, RoundFoot) else foot, relabel)
