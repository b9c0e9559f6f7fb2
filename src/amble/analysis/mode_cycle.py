"""Periods of gaits from the footfall cycle of a hybrid system
(:func:`amble.modelling.footfall_cycle.footfall_cycle`): the modes its post-impact section visits,
one footfall after another, until it is back in the mode it started in.

A walker whose stance feet are modes (left stance, right stance) lands in the other mode at every
footfall: after one footfall it is not on the section of the mode it started on, so its gaits have
an even number of footfalls per period. A one-mode walker, or one whose knee lock changes the mode
between footfalls (unlocked → locked → heel strike → unlocked), has a cycle of one footfall. When
footfalls out of some mode can land in different modes, the cycle is not unique and nothing is
assumed: a period is then whatever the caller asks for.
"""

from __future__ import annotations

import operator
from typing import TYPE_CHECKING

from ..errors import StateError
from ..modelling.footfall_cycle import footfall_cycle

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too: it has the same transitions
    from ..modelling.hybrid import HybridSystem

__all__ = ["footfall_cycle", "footfalls_per_cycle", "section_period"]


def footfalls_per_cycle(system: HybridSystem, mode: str | None = None) -> int:
    """The length of :func:`footfall_cycle` (footfalls until the system is back in ``mode``), 1 when
    that cycle is not unique."""
    cycle = footfall_cycle(system, mode)
    return len(cycle) if cycle else 1


def section_period(system: HybridSystem, period: int | None, mode: str | None = None) -> int:
    """The number of footfalls per period of a gait on the section of ``mode``: ``period`` when it
    is given, which must then be a multiple of the footfall cycle's length (a :class:`StateError`
    naming the cycle otherwise: after another number of footfalls the system is in another mode),
    or the cycle's length when it is ``None``."""
    cycle = footfall_cycle(system, mode)
    c = len(cycle) if cycle else 1
    if period is None:
        return c
    try:
        period = operator.index(period)
    except TypeError:
        raise StateError(f"period must be a whole number of footfalls, got {period!r}") from None
    if cycle and period >= 1 and period % c:
        path = " → ".join((*cycle, cycle[0]))
        raise StateError(f"period {period}: a gait of {system.name} returns to mode {cycle[0]!r} after a multiple "
                         f"of {c} footfalls ({path})")
    return period
