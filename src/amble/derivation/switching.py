"""Switching surfaces of a right-hand side: where a force or controller is not smooth.

``Piecewise`` conditions, the arguments of ``sign``, ``Abs`` and ``Heaviside``, and the pairwise
differences of the arguments of ``Min`` and ``Max`` are functions ``s(q, q̇, t)`` whose zero
set is a kink or a jump of the dynamics. The simulation locates their zero crossings like guards
(an event without a reset: the integrator restarts there, so no step straddles a kink) and ends
a run that slides along one (``sliding``). A surface that depends on parameters only has a
constant sign during a run and is left out.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy as sp

_RELATIONS = (sp.StrictGreaterThan, sp.StrictLessThan, sp.GreaterThan, sp.LessThan)


def _relational_surfaces(cond: sp.Basic) -> list[sp.Expr]:
    if isinstance(cond, _RELATIONS):
        return [sp.sympify(cond.lhs - cond.rhs)]
    if isinstance(cond, (sp.And, sp.Or, sp.Not, sp.Xor)):
        return [s for a in cond.args for s in _relational_surfaces(a)]
    return []


def _surfaces_of(node: sp.Basic) -> list[sp.Expr]:
    if isinstance(node, sp.Piecewise):
        return [s for _, cond in node.args for s in _relational_surfaces(cond)]
    if isinstance(node, (sp.sign, sp.Abs, sp.Heaviside)):
        return [sp.sympify(node.args[0])]
    if isinstance(node, (sp.Min, sp.Max)):
        a = node.args
        return [sp.sympify(a[i] - a[j]) for i in range(len(a)) for j in range(i + 1, len(a))]
    return []


def switching_surfaces(exprs: Iterable[sp.Expr], variables: Iterable[sp.Symbol]) -> list[sp.Expr]:
    """The distinct switching surfaces in ``exprs`` that depend on one of ``variables`` (the
    state and time), in a deterministic order; ``s`` and ``−s`` count once."""
    varset = set(variables)
    found: list[sp.Expr] = []
    seen: set[sp.Expr] = set()
    # Each distinct subexpression is visited once: the equations of a rigid-body tree are DAGs
    # whose shared parts a plain preorder traversal would walk again at every use (exponential
    # in the depth of the tree). The order stays preorder, so the surfaces' order is unchanged.
    visited: set[sp.Basic] = set()
    for e in exprs:
        stack = [sp.sympify(e)]
        while stack:
            node = stack.pop()
            if node in visited:
                continue
            visited.add(node)
            for s in _surfaces_of(node):
                if not (s.free_symbols & varset) or s in seen or -s in seen:
                    continue
                seen.add(s)
                found.append(s)
            if not node.is_Atom:
                stack.extend(reversed(node.args))
    return found
