"""Revisions of a declaration: a counter that every change of a model or system advances.

A built system (compiled kernels and everything derived) is found again by the identity of its
declaration objects and their revisions (:func:`amble.backend.cache.fingerprint`): an edit after
a build — a damping force added to a :class:`~amble.modelling.model.Model`, a transition added to
a :class:`~amble.modelling.hybrid.HybridSystem` — advances a revision, so the next use hashes the
declaration again and builds (or finds in the cache) what it now says, never the stale kernels.

Two ways count a change: assigning an attribute (``m.K = ...``, ``m.tree = ...``) and calling a
method marked :func:`declaration` (those that append to the declaration's lists and dicts).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


class Revised:
    """A declaration with a :attr:`revision`; see the module docstring."""

    _revision = 0

    def __setattr__(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)
        if name != "_revision":
            object.__setattr__(self, "_revision", self._revision + 1)

    @property
    def revision(self) -> int:
        """How many changes this declaration has seen (it only grows)."""
        return self._revision

    def touch(self) -> None:
        """Count a change made outside the declaring methods (e.g. to a list held by the object)."""
        object.__setattr__(self, "_revision", self._revision + 1)


def declaration(method: F) -> F:
    """Mark a method that changes its object's declaration: the revision advances after it (also
    when it raises part-way, since it may have changed something first)."""

    @functools.wraps(method)
    def changed(self: Revised, *args: Any, **kwargs: Any) -> Any:
        try:
            return method(self, *args, **kwargs)
        finally:
            self.touch()

    changed.declares = True  # type: ignore[attr-defined]  # read by the architecture test
    return changed  # type: ignore[return-value]


__all__ = ["Revised", "declaration"]
