"""User input as sympy expressions fit for compiled code: anything that code generation would
fail on far from where it was written is a :class:`~amble.errors.ModelError` here, naming what it
was (a position, a mass, a force ...)."""

from __future__ import annotations

from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef

from ..errors import ModelError
from .text import expr_of

#: Operations sympy keeps unevaluated that compiled code cannot express.
_UNEVALUATED = (sp.Sum, sp.Product, sp.Integral, sp.Derivative, sp.Limit)
_BAD = frozenset((sp.zoo, sp.oo, -sp.oo, sp.nan, sp.I))


def _distinct_nodes(e: sp.Basic) -> list[sp.Basic]:
    """Every distinct subexpression of ``e``, each once: a rigid-body tree's positions share
    their parents' at every level, and sympy's ``atoms`` and ``has`` walk a shared part again at
    every use (exponential in the depth of the tree)."""
    seen: set[int] = set()
    out, stack = [], [e]
    while stack:
        x = stack.pop()
        if id(x) in seen:
            continue
        seen.add(id(x))
        out.append(x)
        stack.extend(x.args)
    return out


def checked_expr(model: Any, value: Any, what: str) -> sp.Expr:
    """``value`` as a sympy expression fit for compiled code, or a :class:`ModelError` naming
    ``what``: no unparsable text, no undefined functions, no infinite, undefined or complex
    constants, no unevaluated sums, products, integrals, derivatives or limits (code generation
    would fail on them far from where they were written).

    ``model`` is the model (text is then read in its symbols, :meth:`Names.parse`) or only its
    name (text is then refused); text is never evaluated (:mod:`amble.modelling.text`)."""
    table = model.symbol_table() if isinstance(value, str) and hasattr(model, "symbol_table") else None
    model = getattr(model, "name", model)
    e = expr_of(value, table, what=f"model {model!r}: {what}")
    if not isinstance(e, sp.Expr):
        raise ModelError(f"model {model!r}: {what} must be an expression, got {value!r}")
    nodes = _distinct_nodes(e)
    undefined = sorted({str(f.func) for f in nodes if isinstance(f, AppliedUndef)})
    if undefined:
        raise ModelError(f"model {model!r}: {what} uses undefined function(s) {', '.join(undefined)}")
    if any(x in _BAD for x in nodes if x.is_Atom):
        raise ModelError(f"model {model!r}: {what} contains an infinite, undefined or complex value: {e}")
    pending = sorted({type(a).__name__ for a in nodes if isinstance(a, _UNEVALUATED)})
    if pending:  # C has no Sum(): it reached the compiler as an undeclared function
        raise ModelError(f"model {model!r}: {what} holds an unevaluated {', '.join(pending)}; write it out "
                         f"(e.g. with .doit()): {e}")
    return e


def checked_matrix(model: Any, value: Any, what: str) -> sp.Matrix:
    """A column (from a flat sequence) or a matrix (from rows, or a sympy matrix) of :func:`checked_expr`
    entries."""
    name = getattr(model, "name", model)
    if isinstance(value, sp.MatrixBase):
        rows = value.tolist()
    elif isinstance(value, (list, tuple)):
        rows = [list(r) if isinstance(r, (list, tuple)) else [r] for r in value]
    else:
        raise ModelError(f"model {name!r}: {what} must be a vector or matrix, got {value!r}")
    if len({len(r) for r in rows}) > 1:
        raise ModelError(f"model {name!r}: {what} has rows of different lengths")
    return sp.Matrix([[checked_expr(model, e, what) for e in r] for r in rows])
