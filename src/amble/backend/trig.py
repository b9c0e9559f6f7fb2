"""``a·sin²u + a·cos²u → a`` in sums, without expanding anything.

Lagrangian mass matrices are full of it: the kinetic energy of a point at ``l·(sin q, −cos q)``
differentiates to ``l²·sin²q + l²·cos²q``, which sympy leaves alone unless asked to
``trigsimp`` — far too slow (and expanding) for large models. This pass looks only at the terms
of each sum, once per distinct subexpression (:func:`amble.modelling.dag.fold`), so it is linear
in the size of the expression graph and never makes an expression larger.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from ..modelling.dag import fold


def _square_of_trig(f: sp.Expr) -> tuple[Any, sp.Expr] | None:
    """``(sin or cos, u)`` if ``f`` is ``sin(u)**2`` or ``cos(u)**2``."""
    if f.is_Pow and f.exp == 2 and isinstance(f.base, (sp.sin, sp.cos)):
        return f.base.func, f.base.args[0]
    return None


def _pair_up(terms: list[sp.Expr]) -> list[sp.Expr] | None:
    """The terms of a sum with pairs ``r·sin²u``, ``r·cos²u`` replaced by ``r`` (``None``: no pair).
    A term is indexed under every squared sine or cosine it has, so ``r`` may itself hold some."""
    keys: list[list[tuple[Any, sp.Expr, sp.Expr]]] = []
    where: dict[tuple[Any, sp.Expr, sp.Expr], list[int]] = {}
    for i, term in enumerate(terms):
        factors = sp.Mul.make_args(term)
        mine = []
        for j, f in enumerate(factors):
            st = _square_of_trig(f)
            if st is not None:
                key = (st[0], st[1], sp.Mul(*factors[:j], *factors[j + 1:]))
                mine.append(key)
                where.setdefault(key, []).append(i)
        keys.append(mine)
    if not where:
        return None
    out, used = [], set()
    for i, term in enumerate(terms):
        if i in used:
            continue
        partner = None
        for func, arg, rest in keys[i]:
            other = sp.cos if func is sp.sin else sp.sin
            partner = next((j for j in where.get((other, arg, rest), ()) if j != i and j not in used), None)
            if partner is not None:
                used.update((i, partner))
                out.append(rest)
                break
        if partner is None:
            out.append(term)
    return out if used else None


def pythagoras(exprs: list[sp.Expr]) -> list[sp.Expr]:
    """``exprs`` with ``r·sin²u + r·cos²u`` replaced by ``r`` inside every sum (equal values)."""
    memo: dict = {}

    def children(e: Any) -> tuple:
        return () if not isinstance(e, sp.Basic) or e.is_Atom else e.args

    def combine(e: Any, kids: list) -> Any:
        if not kids:
            return e
        rebuilt = e if all(a is b for a, b in zip(kids, e.args)) else e.func(*kids)
        # repeated: a pair's common factor may pair with another term (r·sin²a·sin²b +
        # r·sin²b·cos²a + r·cos²b → r·sin²b + r·cos²b → r, a direction with two angles)
        while isinstance(rebuilt, sp.Add):
            paired = _pair_up(list(rebuilt.args))
            if paired is None:
                break
            rebuilt = sp.Add(*paired)
        return rebuilt

    return [fold(sp.sympify(x), children, combine, memo) for x in exprs]
