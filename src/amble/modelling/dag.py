"""Expressions as shared graphs (DAGs): a rigid-body tree's kinematics reuse each parent's
position and rotation in every child, and sympy's ``diff``, ``free_symbols`` and ``srepr`` walk a
shared part again at every use — exponential in the depth of the tree. These visit each distinct
subexpression once."""

from __future__ import annotations

from typing import Any

import sympy as sp


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
    stack = [sp.sympify(expr)]
    while stack:
        e = stack[-1]
        if e in memo:
            stack.pop()
            continue
        if e.is_Atom:
            memo[e] = sp.Integer(1) if e == x else zero
            stack.pop()
            continue
        if not isinstance(e, (sp.Add, sp.Mul, sp.Pow, sp.sin, sp.cos)):
            memo[e] = sp.diff(e, x)
            stack.pop()
            continue
        todo = [a for a in e.args if a not in memo]
        if todo:
            stack.extend(todo)
            continue
        d = [memo[a] for a in e.args]
        if isinstance(e, sp.Add):
            terms = [di for di in d if di != 0]
            out = zero if not terms else terms[0] if len(terms) == 1 else sp.Add(*terms, evaluate=False)
        elif isinstance(e, sp.Mul):
            terms = []
            for i, di in enumerate(d):
                if di != 0:
                    rest = [a for j, a in enumerate(e.args) if j != i]
                    terms.append(sp.Mul(*rest, di, evaluate=False) if di != 1 else sp.Mul(*rest, evaluate=False))
            out = zero if not terms else terms[0] if len(terms) == 1 else sp.Add(*terms, evaluate=False)
        elif isinstance(e, sp.Pow):
            b, n = e.args
            if d[1] != 0:
                out = sp.diff(e, x)
            else:
                out = sp.Mul(n, sp.Pow(b, n - 1), d[0], evaluate=False) if d[0] != 0 else zero
        elif isinstance(e, sp.sin):
            out = sp.Mul(sp.cos(e.args[0]), d[0], evaluate=False) if d[0] != 0 else zero
        else:
            out = sp.Mul(-1, sp.sin(e.args[0]), d[0], evaluate=False) if d[0] != 0 else zero
        memo[e] = out
        stack.pop()
    return memo[sp.sympify(expr)]


def dag_srepr(obj: Any) -> str:
    """A canonical text of expressions (in lists, tuples, dicts or matrices) that writes each
    distinct subexpression once and refers to it by number afterwards — linear in the size of a
    DAG, where ``sympy.srepr`` writes shared parts out at every use."""
    table: dict[sp.Basic, int] = {}
    out: list[str] = []

    def node(e: sp.Basic) -> int:
        stack = [e]
        while stack:
            x = stack[-1]
            if x in table:
                stack.pop()
                continue
            if x.is_Atom:
                out.append(sp.srepr(x))
            else:
                todo = [a for a in x.args if a not in table]
                if todo:
                    stack.extend(todo)
                    continue
                out.append(f"{type(x).__name__}({','.join(str(table[a]) for a in x.args)})")
            table[x] = len(table)
            stack.pop()
        return table[e]

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
