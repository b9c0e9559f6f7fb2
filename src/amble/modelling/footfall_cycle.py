"""The cycle of modes a walker's footfalls take it through (left stance → right stance → …).

A walker's post-impact section lies in the mode a footfall leads into. From there the run may pass
through other modes (a knee locking) before the next footfall; the footfall then leads into the
next section mode. When every section mode leads to exactly one next one, the section modes form
a cycle: one mode for a walker that relabels its legs, two for a walker whose stance feet are
modes. A periodic gait then takes a multiple of the cycle's length in footfalls.
"""

from __future__ import annotations

from typing import Any


def next_section_modes(system: Any, mode: str) -> set[str]:
    """The modes the next footfall from ``mode`` can lead into: the targets of the ``step``
    transitions reachable from ``mode`` through transitions that are not footfalls (terminal ones,
    which end a run, excluded)."""
    seen, stack, out = {mode}, [mode], set()
    while stack:
        m = stack.pop()
        for tr in system.transitions:
            if tr.source != m or tr.terminal is not None:
                continue
            if tr.step:
                out.add(tr.target)
            elif tr.target not in seen:
                seen.add(tr.target)
                stack.append(tr.target)
    return out


def footfall_cycle(system: Any, mode: str | None = None) -> list[str] | None:
    """The section modes of one cycle of footfalls from ``mode`` (default: the system's first
    mode), ``mode`` first: ``["left", "right"]`` for a walker whose stance feet are modes,
    ``[mode]`` for one that relabels its legs. None when a footfall can lead into more than one
    mode (the period is then the caller's choice) or the footfalls never come back to ``mode``."""
    start = mode if mode is not None else system.mode_names[0]
    cycle = [start]
    while True:
        nxt = next_section_modes(system, cycle[-1])
        if len(nxt) != 1:
            return None
        (m,) = nxt
        if m == start:
            return cycle
        if m in cycle:
            return None  # a cycle that does not pass through the start
        cycle.append(m)


def cycle_footfalls(system: Any, mode: str | None = None) -> list[Any]:
    """The footfall transitions of one cycle from ``mode`` (default the first), in order, for a
    walker whose every step is one domain: each section mode left by exactly one footfall and by
    no other transition but terminal ones (a :class:`~amble.errors.ModelError` otherwise, naming
    what is in the way)."""
    from ..errors import ModelError

    cycle = footfall_cycle(system, mode)
    if cycle is None:
        raise ModelError(f"system {system.name!r}: its footfalls do not lead through one cycle of modes")
    out = []
    for m in cycle:
        leaving = [tr for tr in system.transitions if tr.source == m and tr.terminal is None and not tr.forced]
        steps = [tr for tr in leaving if tr.step]
        if len(steps) != 1 or len(leaving) != 1:
            others = ", ".join(tr.name for tr in leaving if not tr.step) or "no footfall"
            raise ModelError(f"system {system.name!r}: a step must be one domain ended by its footfall; mode "
                             f"{m!r} is left by {others} first (modes {list(system.modes)})")
        out.append(steps[0])
    return out
