"""Global starts of the fixed-point search: where :func:`amble.analysis.poincare.find_fixed_point`
turns when neither a walk at the requested parameters nor the model's gait followed there by
continuation finds a gait.

A start that needs more than the return map (the gait optimiser, which itself walks and searches
with :mod:`amble.analysis.poincare`) lives above it and registers here, so that the search does
not import what imports it: :mod:`amble.analysis.collocation_guess` registers the collocated
periodic step when ``amble.analysis`` is imported.

Each entry: ``(name, starts)``, ``starts(system, params, period)`` an iterator of ``(start name,
post-impact state or None, why it failed)``; it raises :class:`~amble.errors.ConvergenceError`
in one line when it does not apply to the system.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

#: the signature of a global start (see the module's docstring)
Starts = Callable[[Any, dict[str, float], int], Iterator[tuple[str, "np.ndarray | None", str]]]

#: the registered global starts, tried in order
GLOBAL_STARTS: list[tuple[str, Starts]] = []


def register(name: str, starts: Starts) -> None:
    """Add (or replace, by ``name``) a global start."""
    GLOBAL_STARTS[:] = [(n, s) for n, s in GLOBAL_STARTS if n != name] + [(name, starts)]


__all__ = ["GLOBAL_STARTS", "Starts", "register"]
