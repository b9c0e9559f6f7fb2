"""Joint limits of a rigid-body tree as guards: a joint reaching its stop is an exact event.

A robot file gives a revolute or prismatic joint a range ``[lower, upper]`` (rad or m; URDF
``<limit>``, MJCF ``limited``/``range``), which the tree keeps by coordinate
(:attr:`RigidTree.limits <amble.modelling.tree.RigidTree.limits>`). Each finite bound of a
coordinate ``q`` is one witness function, positive inside the range:

* ``upper − q`` for the upper bound,
* ``q − lower`` for the lower bound,

each firing where it crosses zero from positive (``direction = −1``), so the event time is
located by the compiled run's root finding like any other guard's. A joint with no coordinate
of its own (a mimic joint, an MJCF equality follower) contributes none — its limits are not the
model's — and neither does a continuous joint.

What happens at the limit is the caller's choice of transition: :meth:`HybridSystem.stop_at_limits
<amble.modelling.hybrid.HybridSystem.stop_at_limits>` ends the run there with the status
:data:`STATUS`, the transition named ``<coordinate>_<bound>_limit`` (:func:`limit_of` reads the
name back); a :class:`LimitGuard`'s ``guard`` may also fire a transition of one's own.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from ..errors import ModelError
from .transitions import Guard

#: the status of a run ended by :meth:`HybridSystem.stop_at_limits`
STATUS = "joint_limit"
#: the bounds of a range, in the order a coordinate's guards are listed
BOUNDS = ("lower", "upper")
_NAME = re.compile(r"^(?P<coordinate>.+)_(?P<bound>lower|upper)_limit(?:@(?P<mode>.+))?$")


@dataclass(frozen=True)
class LimitGuard:
    """One bound of a joint's range as a guard of the model's state.

    ``coordinate``: the model coordinate (its name); ``bound``: ``"lower"`` or ``"upper"``;
    ``value``: the bound (rad for a revolute joint, m for a prismatic one); ``guard``: the
    witness ``upper − q`` or ``q − lower``, positive inside the range, firing from positive.
    """

    coordinate: str
    bound: str
    value: float
    guard: Guard

    @property
    def name(self) -> str:
        """The transition name :meth:`HybridSystem.stop_at_limits` gives it:
        ``<coordinate>_<bound>_limit``."""
        return f"{self.coordinate}_{self.bound}_limit"


def limit_guards(model: Any) -> list[LimitGuard]:
    """The guards of every finite joint limit of ``model``'s rigid-body tree, by coordinate in
    the model's order, lower bound first (an empty list for a model without a tree or limits).

    A range with ``lower > upper`` is a :class:`ModelError` naming the coordinate: no state
    would lie inside it."""
    tree = getattr(model, "tree", None)
    if tree is None:
        return []
    import sympy as sp  # here: reading a transition's name back (limit_of) needs no SymPy

    out: list[LimitGuard] = []
    for q in model.q:
        lower, upper = tree.limits.get(str(q), (None, None))
        lower, upper = _finite(lower), _finite(upper)
        if lower is not None and upper is not None and lower > upper:
            raise ModelError(f"model {model.name!r}: coordinate {str(q)!r} has the empty range "
                             f"[{lower:g}, {upper:g}] (lower above upper)")
        if lower is not None:
            out.append(LimitGuard(str(q), "lower", lower, Guard(q - sp.Float(lower, 17), -1)))
        if upper is not None:
            out.append(LimitGuard(str(q), "upper", upper, Guard(sp.Float(upper, 17) - q, -1)))
    return out


def _finite(value: float | None) -> float | None:
    """A bound as a float, or ``None`` for no bound (an infinite one bounds nothing)."""
    if value is None:
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def transition_name(guard: LimitGuard, mode: str | None = None) -> str:
    """The name of the terminal transition of ``guard`` in ``mode`` (``None``: a system of one
    mode): ``<coordinate>_<bound>_limit``, followed by ``@<mode>`` when the system has several."""
    return guard.name if mode is None else f"{guard.name}@{mode}"


def limit_of(transition: str) -> tuple[str, str] | None:
    """``(coordinate, bound)`` of a transition made by :meth:`HybridSystem.stop_at_limits`, read
    from its name (``"knee_upper_limit"`` → ``("knee", "upper")``); ``None`` for any other name."""
    m = _NAME.match(transition)
    return None if m is None else (m["coordinate"], m["bound"])
