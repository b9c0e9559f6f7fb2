"""The footfall cycle of a hybrid system: the modes its post-impact section visits, one footfall
after another, until it is back in the mode it started in.

A walker whose stance feet are modes (left stance, right stance) lands in the other mode at every
footfall: after one footfall it is not on the section of the mode it started on, so its gaits have
an even number of footfalls per period. A one-mode walker, or one whose knee lock changes the mode
between footfalls (unlocked → locked → heel strike → unlocked), has a cycle of one footfall.

The cycle is read from the declared transitions only (``source``, ``target``, ``step``,
``terminal``): from a mode, the transitions that are not footfalls (``step=False``, e.g. a knee
lock, a touchdown) are followed to every mode they reach, and the footfalls (``step=True``) out of
those modes name the mode of the next post-impact state. When they name more than one (the system
may land in either), the cycle is not unique and nothing is assumed: a period is then whatever the
caller asks for.
"""

from __future__ import annotations

import operator
from typing import TYPE_CHECKING, Any

from ..errors import StateError

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too: it has the same transitions
    from ..modelling.hybrid import HybridSystem

__all__ = ["footfall_cycle", "footfalls_per_cycle", "section_period"]


def _next_mode(transitions: list[Any], mode: str) -> str | None:
    """The mode of the post-impact state one footfall after a post-impact state in ``mode``:
    ``None`` when no footfall can follow or footfalls into different modes can."""
    seen, todo = {mode}, [mode]
    landing: set[str] = set()
    while todo:
        m = todo.pop()
        for tr in transitions:
            if tr.source != m or tr.terminal:
                continue
            target = tr.target or tr.source
            if tr.step:
                landing.add(target)
            elif target not in seen:
                seen.add(target)
                todo.append(target)
    return landing.pop() if len(landing) == 1 else None


def footfall_cycle(system: HybridSystem, mode: str | None = None) -> tuple[str, ...] | None:
    """The modes of the post-impact states of successive footfalls from ``mode`` (default: the
    system's first mode) until the system is back in ``mode``, ``mode`` first: ``("left",
    "right")`` for a walker whose stance feet are modes, ``("unlocked",)`` for a kneed biped.
    ``None`` when the footfalls do not form one cycle through ``mode`` (from some mode on the way,
    footfalls lead into different modes, none can happen, or they never lead back)."""
    transitions = list(system.transitions)
    start = mode if mode is not None else next(iter(system.modes))
    cycle = [start]
    while True:
        nxt = _next_mode(transitions, cycle[-1])
        if nxt is None or (nxt != start and nxt in cycle):
            return None
        if nxt == start:
            return tuple(cycle)
        cycle.append(nxt)


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
