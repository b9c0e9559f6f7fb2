"""Cells of a sweep result file as text: how a value is written, exactly, and read back.

A float is written by ``repr`` (the shortest text that reads back as the same double, so a
continuation seed read back from the file is bit-identical to the computed one), an integer in
decimal, a boolean ``true``/``false``, ``None`` as an empty cell. :func:`fmt_value` formats one
value; :func:`fmt_floats` and :func:`fmt_ints` a whole column at once with the same result, at
a fraction of the cost per cell (one C-level ``map`` over the column, no type dispatch per
value): a task of a basin map formats its block of cells with them and returns
:class:`TextRows`, which the result store appends without looking at each value again.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from typing import Any

import numpy as np

#: Column types of sweep rows: how :meth:`SweepResult.records` reads a stored text cell back
#: (an empty cell is ``None``, or NaN for ``float``).
COLUMN_TYPES = ("int", "float", "bool", "str", "json")


def fmt_value(v: Any) -> str:
    """A cell as text: floats by ``repr`` (round-trips exactly, so a seed read back from the file
    is bit-identical), booleans ``true``/``false``, ``None`` empty."""
    if isinstance(v, bool) or v is None:
        return "" if v is None else str(v).lower()
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return str(v)


def fmt_floats(values: Iterable[float] | np.ndarray) -> list[str]:
    """:func:`fmt_value` of each value as a float (``repr`` of the double; ``nan``, ``inf``,
    ``-0.0`` as ``repr`` writes them), for a whole column in one pass."""
    return list(map(repr, np.asarray(values, dtype=float).ravel().tolist()))


def fmt_ints(values: Iterable[int] | np.ndarray) -> list[str]:
    """:func:`fmt_value` of each value as an integer (decimal), for a whole column in one pass."""
    return list(map(str, np.asarray(values, dtype=np.int64).ravel().tolist()))


class TextRows(list):
    """Rows already written as text (tuples of cells in the file's column order, each as
    :func:`fmt_value` writes it): what a sweep task returns so that the client process appends
    them to the result file without formatting or checking each value again."""


def parse_value(text: str, kind: str) -> Any:
    """A stored cell (:func:`fmt_value`) back as a value of the column type ``kind``."""
    if kind == "str":
        return text
    if text == "":
        return math.nan if kind == "float" else None
    if kind == "float":
        return float(text)
    if kind == "int":
        return int(text)
    if kind == "bool":
        return text == "true"
    if kind == "json":
        return json.loads(text)
    raise ValueError(f"unknown column type {kind!r}; known: {', '.join(COLUMN_TYPES)}")


__all__ = ["COLUMN_TYPES", "TextRows", "fmt_floats", "fmt_ints", "fmt_value", "parse_value"]
