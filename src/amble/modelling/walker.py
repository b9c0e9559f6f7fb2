"""Walkers on a slope: a footfall, joint locks and falls from a few declarations.

The walking surface is a plane through the stance foot (the origin of every step's frame)
descending along ``+x`` at angle ``slope`` (:mod:`amble.modelling.contact.ground`); the footfall
is a contact's impact (:func:`amble.modelling.contact.heel_strike`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ..errors import ModelError
from .contact import RoundFoot, heel_strike, height_above_slope
from .domain import interval
from .hybrid import Guard, HybridSystem, Lock
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
    step_height: Any = 0,
) -> Walker:
    """A one-mode walker: heel strike of ``foot`` on the slope (a step) and a fall of ``hip``.

    ``start`` is the default initial state, ``guess`` the default fixed-point guess (both in
    ``model.state_names`` order). A walker that makes no footfall for ``max_step_time`` seconds,
    or whose hip reaches the ground, has fallen. ``mirror``: see :class:`Walker`; ``margin``:
    the footfall's enabling margin, and ``stance`` the stance foot the swing ``foot`` must be ahead
    of (needed with round feet, whose stance contact moves), and ``step_height`` the height of
    the ground the foot meets above the stance foot's slope plane (e.g. a parameter ``step``, 0 by
    default, to disturb one step), see :func:`heel_strike`.
    """
    sys_ = Walker(model.name, {model.name: model}, max_step_time=max_step_time, hip=hip, slope=slope,
                  mirror=mirror, doc=doc)
    guard, reset = heel_strike(model, foot, slope, relabel, margin, stance, step_height)
    sys_.transition("heel_strike", model.name, guard, reset, step=True)
    sys_.terminal("hip_on_ground", model.name, Guard(height_above_slope(model, hip, slope), -1), status="fell")
    if start is not None:
        sys_.default_start[model.name] = list(start)
    sys_.fixed_point_guess = list(guess) if guess is not None else (list(start) if start is not None else None)
    return sys_
