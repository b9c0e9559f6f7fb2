"""Walkers on a slope: heel-strike guards, impact resets and falls from a few declarations.

The walking surface is a plane through the stance foot (the origin of every step's frame)
descending along ``+x`` at angle ``slope``. Its unit normal is ``n = (sin γ, cos γ)`` in 2D
(``(sin γ, 0, cos γ)`` in 3D) and the downhill direction along it is ``d = (cos γ, −sin γ)``.
A point's height above the ground is ``n·p``; it is ahead of the stance foot when ``d·p > 0``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp

from ..errors import ModelError
from .contact import RoundFoot
from .domain import interval
from .hybrid import Guard, HybridSystem, Impact, Lock
from .model import Model

_AXES = {"x": 0, "y": 1, "z": 2}

#: slopes a walker can stand on (rad); a slope parameter gets this domain unless it declares one
SLOPES = interval(-math.pi / 4, math.pi / 4)


@dataclass
class Walker(HybridSystem):
    """A hybrid system that walks on a slope: what analysis and drawing need beyond modes and
    transitions.

    ``hip``: the point a camera follows and whose fall ends a run; ``slope``: the ground's
    angle (a parameter symbol or a number, rad; the surface descends along +x through each
    step's stance foot); ``mirror``: ``"y"`` when the relabelling at a footfall mirrors the
    lateral axis (a 3D walker whose left and right legs swap roles), so world-frame kinematics
    reflect that axis at every ``step`` transition.
    """

    hip: str | None = None
    slope: Any = 0.0
    mirror: str | None = None
    #: a walker without a footfall for this long has fallen (s; 5 s unless the model says otherwise)
    max_step_time: float = 5.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.mirror is not None and self.mirror not in _AXES:
            raise ModelError(f"walker {self.name!r}: mirror must be one of x, y, z or None, got {self.mirror!r}")
        if self.hip is not None and self.hip not in self.point_names:
            raise ModelError(f"walker {self.name!r}: hip {self.hip!r} is not a point of the model")
        for m in self.modes.values():
            if self.slope in m.params and str(self.slope) not in m.domains:
                m.declare_domains(**{str(self.slope): SLOPES})

    def frame_change(self, transition: str) -> tuple[str | None, tuple[float, float, float]]:
        shift, flip = super().frame_change(transition)
        if self.mirror is not None and self._transition(transition).step:
            flip = tuple(-f if i == _AXES[self.mirror] else f for i, f in enumerate(flip))  # type: ignore[assignment]
        return shift, flip

    def slope_value(self, params: Mapping[str, float]) -> float:
        """The ground angle (rad) at these parameter values (a parameter name resolved in them)."""
        s = self.slope
        if isinstance(s, (int, float)):
            return float(s)
        return float(params.get(str(s), self.parameters.get(str(s), 0.0)))


def _vec2(model: Model, a: Any, b: Any) -> sp.Matrix:
    return sp.Matrix([a, b]) if model.dims == 2 else sp.Matrix([a, 0, b])


def height_above_slope(model: Model, point: str, slope: Any) -> sp.Expr:
    """Height (m) of a named point above the slope plane through the origin, along its normal."""
    n = _vec2(model, sp.sin(slope), sp.cos(slope))
    return (n.T * model.points[point])[0, 0]


def distance_along_slope(model: Model, point: str, slope: Any) -> sp.Expr:
    """Distance (m) of a named point ahead of the origin, measured downhill along the slope."""
    d = _vec2(model, sp.cos(slope), -sp.sin(slope))
    return (d.T * model.points[point])[0, 0]


#: A footfall needs the foot ahead of the stance foot by this fraction of the model's size.
STEP_MARGIN = 1e-6


def model_size(model: Model) -> sp.Expr:
    """A length of the model in its current configuration: the root mean square distance of its
    named points from the origin (the stance foot) — the scale of an enabling margin."""
    pts = list(model.points.values())
    if not pts:
        return sp.Integer(1)
    return sp.sqrt(sum(((p.T * p)[0, 0] for p in pts), sp.Integer(0)) / len(pts))


def heel_strike(model: Model, foot: str | RoundFoot, slope: Any, relabel: Mapping[Any, Any],
                margin: Any = None, stance: str | RoundFoot | None = None) -> tuple[Guard, Impact]:
    """Guard and reset of a footfall: ``foot`` reaches the slope while ahead of the stance foot
    by more than ``margin`` (default :data:`STEP_MARGIN` × :func:`model_size`, so that legs
    passing each other — the foot at the stance foot up to round-off — are no footfall),
    followed by a plastic impact and the leg relabelling.

    ``foot`` is a point (a point foot) or a :class:`~amble.modelling.contact.RoundFoot`: then its
    contact point meets the slope and the impact constrains the material point of the foot at
    the contact (its ``rolling`` point, which also becomes the next step's origin). ``stance``
    names the stance foot's contact (a point or a ``RoundFoot``) that the foot must be ahead
    of; by default the origin, where a point stance foot stands.
    """
    contact = foot.contact if isinstance(foot, RoundFoot) else foot
    if margin is None:
        margin = STEP_MARGIN * model_size(model)
    ahead = distance_along_slope(model, contact, slope)
    if stance is not None:
        ahead -= distance_along_slope(model, stance.contact if isinstance(stance, RoundFoot) else stance, slope)
    # unevaluated: deciding ``ahead > margin`` asks sympy for signs of the whole expression, which
    # for a rigid-body tree's positions (shared graphs) takes minutes; the compiled code decides it
    guard = Guard(height_above_slope(model, contact, slope), -1, sp.StrictGreaterThan(ahead, margin, evaluate=False))
    return guard, Impact(foot.rolling if isinstance(foot, RoundFoot) else foot, relabel)


def joint_lock(constraint: Any, relabel: Mapping[Any, Any] | None = None) -> tuple[Guard, Lock]:
    """Guard and reset of a joint that locks when ``constraint`` (e.g. ``shank − thigh``, thesis
    Eq. 27) falls through zero: the lock impulse (Eq. 28), then the mode without the joint
    (``relabel`` may omit coordinates both modes share)."""
    return Guard(constraint, -1), Lock(constraint, relabel or {})


def walker(
    model: Model,
    *,
    foot: str | RoundFoot,
    hip: str,
    slope: Any,
    relabel: Mapping[Any, Any],
    start: Sequence[float] | None = None,
    guess: Sequence[float] | None = None,
    max_step_time: float = 5.0,
    mirror: str | None = None,
    doc: str = "",
    margin: Any = None,
    stance: str | RoundFoot | None = None,
) -> Walker:
    """A one-mode walker: heel strike of ``foot`` on the slope (a step) and a fall of ``hip``.

    ``start`` is the default initial state, ``guess`` the default fixed-point guess (both in
    ``model.state_names`` order). A walker that makes no footfall for ``max_step_time`` seconds,
    or whose hip reaches the ground, has fallen. ``mirror``: see :class:`Walker`; ``margin``:
    the footfall's enabling margin, and ``stance`` the stance foot the swing ``foot`` must be ahead
    of (needed with round feet, whose stance contact moves), see :func:`heel_strike`.
    """
    sys_ = Walker(model.name, {model.name: model}, max_step_time=max_step_time, hip=hip, slope=slope,
                  mirror=mirror, doc=doc)
    guard, reset = heel_strike(model, foot, slope, relabel, margin, stance)
    sys_.transition("heel_strike", model.name, guard, reset, step=True)
    sys_.terminal("hip_on_ground", model.name, Guard(height_above_slope(model, hip, slope), -1), status="fell")
    if start is not None:
        sys_.default_start[model.name] = list(start)
    sys_.fixed_point_guess = list(guess) if guess is not None else (list(start) if start is not None else None)
    return sys_
