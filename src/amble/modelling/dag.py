"""Expressions as shared graphs (DAGs): a rigid-body tree's kinematics reuse each parent's
position and rotation in every child, and sympy's ``diff``, ``free_symbols`` and ``srepr`` walk a
shared part again at every use — exponential in the depth of the tree. These visit each distinct
subexpression once."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import sympy as sp


def fold(root: Any, children: Callable[[Any], Sequence[Any]], combine: Callable[[Any, list[Any]], Any],
         memo: dict) -> Any:
    """Post-order fold over a DAG: ``memo[e] = combine(e, [memo[c] for c in children(e)])`` for
    every node reachable from ``root``, each computed once (iteratively: trees are deep)."""
    stack = [root]
    while stack:
        e = stack[-1]
        if e in memo:
            stack.pop()
            continue
        kids = children(e)
        todo = [c for c in kids if c not in memo]
        if todo:
            stack.extend(todo)
            continue
        memo[e] = combine(e, [memo[c] for c in kids])
        stack.pop()
    return memo[root]


def free_symbols(expr: Any) -> set[sp.Symbol]:
    """Free symbols of an expression or matrix, visiting each shared subexpression once (the
    expressions of a rigid-body tree are DAGs: a plain traversal would revisit shared parts)."""
    roots = list(expr) if isinstance(expr, sp.MatrixBase) else [sp.sympify(expr)]
    seen: set[int] = set()
    out: set[sp.Symbol] = set()
    stack = roots
    while stack:
        x = stack.pop()
        if id(x) in seen:
            continue
        seen.add(id(x))
        if x.is_Symbol:
            out.add(x)
        elif not x.is_Atom:
            stack.extend(x.args)
    return out


def dag_diff(expr: Any, x: sp.Symbol, memo: dict | None = None) -> sp.Expr:
    """``∂expr/∂x`` visiting each shared subexpression once (sympy's ``diff`` revisits them,
    which is exponential in the depth of a rigid-body tree's kinematics). The result shares
    subexpressions with ``expr``; it is built unevaluated where that keeps sharing."""
    memo = {} if memo is None else memo
    zero = sp.Integer(0)
    rules = (sp.Add, sp.Mul, sp.Pow, sp.sin, sp.cos, sp.atan2)

    def children(e: sp.Basic) -> Sequence[sp.Basic]:
        return e.args if isinstance(e, rules) and not e.is_Atom else ()

    def combine(e: sp.Basic, d: list[sp.Expr]) -> sp.Expr:
        if e.is_Atom:
            return sp.Integer(1) if e == x else zero
        if not isinstance(e, rules):
            return sp.diff(e, x)
        if isinstance(e, sp.Add):
            terms = [di for di in d if di != 0]
            return zero if not terms else terms[0] if len(terms) == 1 else sp.Add(*terms, evaluate=False)
        if isinstance(e, sp.Mul):
            terms = []
            for i, di in enumerate(d):
                if di != 0:
                    rest = [a for j, a in enumerate(e.args) if j != i]
                    terms.append(sp.Mul(*rest, di, evaluate=False) if di != 1 else sp.Mul(*rest, evaluate=False))
            return zero if not terms else terms[0] if len(terms) == 1 else sp.Add(*terms, evaluate=False)
        if isinstance(e, sp.Pow):
            b, n = e.args
            if d[1] != 0:
                return sp.diff(e, x)
            return sp.Mul(n, sp.Pow(b, n - 1), d[0], evaluate=False) if d[0] != 0 else zero
        if isinstance(e, sp.atan2):  # atan2(y, x)' = (x y' − y x') / (x² + y²)
            (y, xx), (dy, dx) = e.args, d
            if dy == 0 and dx == 0:
                return zero
            num = sp.Add(sp.Mul(xx, dy, evaluate=False), sp.Mul(-1, y, dx, evaluate=False), evaluate=False)
            den = sp.Add(sp.Pow(xx, 2, evaluate=False), sp.Pow(y, 2, evaluate=False), evaluate=False)
            return sp.Mul(num, sp.Pow(den, -1, evaluate=False), evaluate=False)
        if isinstance(e, sp.sin):
            return sp.Mul(sp.cos(e.args[0]), d[0], evaluate=False) if d[0] != 0 else zero
        return sp.Mul(-1, sp.sin(e.args[0]), d[0], evaluate=False) if d[0] != 0 else zero

    return fold(sp.sympify(expr), children, combine, memo)


def dag_srepr(obj: Any) -> str:
    """A canonical text of expressions (in lists, tuples, dicts or matrices) that writes each
    distinct subexpression once and refers to it by number afterwards — linear in the size of a
    DAG, where ``sympy.srepr`` writes shared parts out at every use."""
    table: dict[sp.Basic, int] = {}
    out: list[str] = []

    def text(x: sp.Basic, ids: list[int]) -> int:
        out.append(sp.srepr(x) if x.is_Atom else f"{type(x).__name__}({','.join(map(str, ids))})")
        return len(table)  # the index it gets, in order of first completion

    def node(e: sp.Basic) -> int:
        return fold(e, lambda x: () if x.is_Atom else x.args, text, table)

    def walk(o: Any) -> str:
        if isinstance(o, sp.MatrixBase):
            return "M" + repr(o.shape) + "[" + ",".join(walk(e) for e in o) + "]"
        if isinstance(o, sp.Basic):
            return f"#{node(o)}"
        if isinstance(o, (list, tuple)):
            return "(" + ",".join(walk(e) for e in o) + ")"
        if isinstance(o, dict):
            return "{" + ",".join(f"{walk(k)}:{walk(v)}" for k, v in o.items()) + "}"
        return repr(o)

    top = walk(obj)
    return top + "|" + ";".join(out)


def dag_subs(expr: Any, mapping: dict, memo: dict | None = None) -> Any:
    """``expr`` (an expression or matrix) with the symbols of ``mapping`` replaced, visiting each
    shared subexpression once and rebuilding it once (so the result shares as ``expr`` does;
    sympy's ``subs`` and ``xreplace`` rebuild a shared part at every use). ``memo`` may be shared
    between calls on expressions with common parts."""
    memo = {} if memo is None else memo
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(lambda e: dag_subs(e, mapping, memo))

    def children(e: sp.Basic) -> Sequence[sp.Basic]:
        return () if e.is_Atom else e.args

    def combine(e: sp.Basic, args: list[Any]) -> Any:
        if e.is_Atom:
            return mapping.get(e, e)
        return e if all(a is b for a, b in zip(args, e.args)) else e.func(*args)

    return fold(sp.sympify(expr), children, combine, memo)
