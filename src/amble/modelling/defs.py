"""Named intermediate quantities of a symbolic recursion (a rigid-body tree's kinematics and
dynamics): each non-trivial expression gets a fresh symbol once, and expressions of those
symbols expand back to a shared graph (DAG) of q, q̇ and parameters."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import sympy as sp

from .dag import fold


class Defs:
    """Intermediate quantities of a recursion: each non-trivial expression is named by a fresh
    symbol, so every step works on small expressions (sympy's cost grows with their size).

    :meth:`expand` turns an expression of these symbols back into one of q, q̇ and parameters,
    as a DAG: each definition is rebuilt once, unevaluated (no flattening, no distribution of
    numeric factors), and shared by every use — common subexpressions for code generation.
    """

    def __init__(self) -> None:
        self._defs: dict[sp.Symbol, sp.Expr] = {}
        self._names: dict[sp.Expr, sp.Symbol] = {}
        self._done: dict[sp.Basic, sp.Basic] = {}

    def __call__(self, e: Any) -> sp.Expr:
        e = sp.sympify(e)
        if e.is_Atom or isinstance(e, sp.Function) or (
                e.is_Mul and len(e.args) == 2 and e.args[0].is_Number and e.args[1].is_Atom):
            return e
        # an expression defined before keeps its name: recursions meet the same quantity often
        # (a point on a body and its centre of mass, M's and h's shared kinematics, a second derive)
        s = self._names.get(e)
        if s is None:
            s = self._names[e] = sp.Dummy(f"k{len(self._defs)}")
            self._defs[s] = e
        return s

    def vec(self, m: sp.Matrix) -> sp.Matrix:
        return m.applyfunc(self)

    def needed(self, exprs: Any) -> list[tuple[sp.Symbol, sp.Expr]]:
        """The definitions that ``exprs`` use, directly or not, in an order where each comes
        after those it uses."""
        used: set[sp.Symbol] = set()
        stack = [e for e in exprs]
        seen: set[sp.Basic] = set()
        while stack:
            x = sp.sympify(stack.pop())
            if x in seen:
                continue
            seen.add(x)
            if isinstance(x, sp.Dummy) and x in self._defs:
                used.add(x)
                stack.append(self._defs[x])
            elif not x.is_Atom:
                stack.extend(x.args)
        return [(s, e) for s, e in self._defs.items() if s in used]

    def expand(self, e: Any) -> Any:
        """``e`` (an expression or matrix of the defined symbols) in q, q̇ and parameters."""
        if isinstance(e, sp.MatrixBase):
            return e.applyfunc(self.expand)
        defs = self._defs

        def children(x: sp.Basic) -> Sequence[sp.Basic]:
            if isinstance(x, sp.Dummy) and x in defs:
                return (defs[x],)  # a defined symbol stands for its definition
            return () if x.is_Atom else x.args

        def combine(x: sp.Basic, args: list[Any]) -> Any:
            if isinstance(x, sp.Dummy) and x in defs:
                return args[0]
            if x.is_Atom:
                return x
            # unevaluated: an evaluated power of an expanded sum asks the whole graph for its
            # assumptions (is it zero, infinite, real?) by a plain walk — exponential in the depth
            # (the 30-DOF humanoid's kinetic energy: 5 s for 163 squares)
            return x.func(*args, evaluate=False) if isinstance(x, (sp.Add, sp.Mul, sp.Pow)) else x.func(*args)

        return fold(sp.sympify(e), children, combine, self._done)

    def substituted(self, mapping: dict) -> Defs:
        """The same names, each defined with the symbols of ``mapping`` replaced (a model with
        some coordinates tied to others: the definitions are small, so each is replaced alone)."""
        out = Defs()
        out._defs = {s: e.xreplace(mapping) for s, e in self._defs.items()}
        return out
