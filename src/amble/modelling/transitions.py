"""Transitions of a hybrid system as declarations: the guard (witness function), the reset
(:class:`Impact`, :class:`Lock`, :class:`Explicit`) and the transition that joins them; how they
are validated against their modes and compiled lives in :mod:`amble.modelling.hybrid` and the
backend."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Guard:
    """Witness function of a transition.

    Parameters
    ----------
    expr:
        ``g(q, q̇, t)`` in the source mode's symbols.
    direction:
        ``-1``: fires when ``g`` goes from ``> 0`` to ``≤ 0`` (default); ``+1``: from ``< 0`` to
        ``≥ 0``; ``0``: either way.
    enabled:
        Optional sympy boolean (e.g. ``foot_x > 0``) that must hold at the crossing; crossings
        where it is false are ignored (a swing foot scuffing behind the stance foot).
    """

    expr: Any
    direction: int = -1
    enabled: Any = None


class Reset:
    """Base class of resets."""

    #: name of the point whose pre-event position becomes the new origin (None: no shift)
    shift_point: str | None = None


@dataclass
class Impact(Reset):
    """Plastic impact of ``point`` with the ground, then relabelling.

    The post-impact velocity solves ``M_e (q̇e⁺ − q̇e⁻) = Jᵀλ, J q̇e⁺ = 0`` for the model extended
    with the stance-foot position (which may now lift off), ``J`` being the Jacobian of the
    impacting point in the extended coordinates. ``relabel`` gives each coordinate of the
    target mode as an expression of the source coordinates (e.g. ``{stance: swing,
    swing: stance}``); velocities follow by the chain rule.
    """

    point: str
    relabel: Mapping[Any, Any]

    @property
    def shift_point(self) -> str:  # type: ignore[override]
        return self.point


@dataclass
class Lock(Reset):
    """Impulsive constraint ``c(q) = 0`` (e.g. a knee lock ``shank − thigh``), then relabelling.

    The impulse solves ``M (q̇⁺ − q̇⁻) = ∇cᵀλ, ∇c q̇⁺ = 0``; ``relabel`` gives the target
    mode's coordinates in terms of the source coordinates.
    """

    constraint: Any
    relabel: Mapping[Any, Any]


@dataclass
class Explicit(Reset):
    """A reset written out: target coordinates and velocities as expressions of the source state.

    ``q`` and ``qd`` are mappings target-name → expression, or sequences in target order (a
    sympy Matrix such as ``J*q`` or ``H_g*q̇`` works). ``shift`` optionally names a point whose
    pre-event position becomes the new origin (the new stance foot).
    """

    q: Any
    qd: Any
    shift: str | None = None

    @property
    def shift_point(self) -> str | None:  # type: ignore[override]
        return self.shift


@dataclass
class Transition:
    name: str
    source: str
    target: str
    guard: Guard
    reset: Reset | None
    terminal: str | None = None
    step: bool = False
    #: name of the transition taken instead of ending the run as ``zeno`` when firings of this
    #: one accumulate (a unilateral contact coming to rest); None: the run ends as ``zeno``
    rest: str | None = None
    #: True: the transition has no guard crossing of its own; it is only taken as another
    #: transition's ``rest`` (its guard is the constant 1, which never crosses)
    forced: bool = False
