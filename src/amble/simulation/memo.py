"""A small table of values worked out once per inputs, for objects that may be replaced.

Keys are tuples of plain values that start with the ids of the objects a value belongs to (a
system, its compiled kernels, an options object); an id is reused once its object is gone, so
each value is stored with those very objects and a hit needs them again (``is``, never ``==``:
comparing systems would cost more than the work saved). The table is emptied at ``limit``
entries: a caller that makes a new object or value per call would fill it.
"""

from __future__ import annotations

from typing import Any


class Memo:
    """``get(key, *owners)`` → the value stored by ``put(key, value, *owners)`` with the same
    owner objects, else ``None``."""

    def __init__(self, limit: int) -> None:
        self._table: dict[tuple, tuple[tuple, Any]] = {}
        self._limit = limit

    def get(self, key: tuple, *owners: Any) -> Any:
        hit = self._table.get(key)
        if hit is None:
            return None
        held = hit[0]
        if len(held) != len(owners):
            return None
        for a, b in zip(held, owners):
            if a is not b:
                return None
        return hit[1]

    def put(self, key: tuple, value: Any, *owners: Any) -> None:
        if len(self._table) >= self._limit:
            self._table.clear()
        self._table[key] = (owners, value)

    def clear(self) -> None:
        self._table.clear()


__all__ = ["Memo"]
