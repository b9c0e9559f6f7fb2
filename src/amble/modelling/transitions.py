"""Transitions of a hybrid system as declarations: the guard (witness function), the reset
(:class:`Impact`, :class:`Lock`, :class:`Explicit`) and the transition that joins them.

What a layer does with a reset — validate it, derive its impulse, generate its C, export it to
CasADi, display it — is one :class:`ResetVisitor` in that layer, with one method per kind of
reset; a reset hands itself to the right method (:meth:`Reset.accept`). No module asks a reset
for its type: a new kind of reset is a class here and one method in each visitor's base, and
every operation that does not know it yet says so by name (the base methods raise).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from ..errors import ModelError

T = TypeVar("T")


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
    #: name of the point whose impact with the ground this reset is (None: not a ground impact)
    impact_point: str | None = None
    #: the target state written out, ``(q, qd)`` as given (None: the reset is derived, impulsive)
    written: tuple[Any, Any] | None = None

    def accept(self, visitor: ResetVisitor[T]) -> T:
        """``visitor``'s method for this kind of reset, applied to it."""
        raise ModelError(f"{type(self).__name__} is not a kind of reset amble knows (Impact, Lock or Explicit)")


class ResetVisitor(Generic[T]):
    """One operation over every kind of reset (see the module docstring).

    :class:`Impact` and :class:`Lock` are *impulsive* (the post-event velocity solves an impulse
    problem; the coordinates are relabelled): unless overridden, both go to :meth:`impulsive`.
    ``what`` names the transition in the messages of the methods a visitor does not provide."""

    what = "reset"

    def impact(self, reset: Impact) -> T:
        return self.impulsive(reset)

    def lock(self, reset: Lock) -> T:
        return self.impulsive(reset)

    def impulsive(self, reset: Impact | Lock) -> T:
        raise ModelError(f"{self.what}: an impulsive reset ({type(reset).__name__}) is not supported here")

    def explicit(self, reset: Explicit) -> T:
        raise ModelError(f"{self.what}: an explicit reset is not supported here")


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

    @property
    def impact_point(self) -> str:  # type: ignore[override]
        return self.point

    def accept(self, visitor: ResetVisitor[T]) -> T:
        return visitor.impact(self)


@dataclass
class Lock(Reset):
    """Impulsive constraint ``c(q) = 0`` (e.g. a knee lock ``shank − thigh``), then relabelling.

    The impulse solves ``M (q̇⁺ − q̇⁻) = ∇cᵀλ, ∇c q̇⁺ = 0``; ``relabel`` gives the target
    mode's coordinates in terms of the source coordinates.
    """

    constraint: Any
    relabel: Mapping[Any, Any]

    def accept(self, visitor: ResetVisitor[T]) -> T:
        return visitor.lock(self)


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

    @property
    def written(self) -> tuple[Any, Any]:  # type: ignore[override]
        return self.q, self.qd

    def accept(self, visitor: ResetVisitor[T]) -> T:
        return visitor.explicit(self)


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
