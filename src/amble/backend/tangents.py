"""Jacobians of generated expressions by sparse forward-mode differentiation of their DAG.

Differentiating a 3D humanoid's mass matrix and bias as expressions takes sympy minutes (every
entry is a large unexpanded tree, and each derivative is simplified on construction). Here each
distinct subexpression is a node of a straight-line program, ``vᵢ = op(children)``, and its
derivative with respect to each input it depends on is printed from the elementary rule of
``op`` (sum, product, power, sine, cosine; other functions by differentiating them in their
arguments only) — so the cost is that of printing the program, and only the non-zero partials
(a node depends on few coordinates) are computed at run time.

Derivatives of switching functions (``DiracDelta``) are zero: a jump of a right-hand side is an
event of its own, whose effect enters through the saltation matrix there.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import sympy as sp

from ..modelling.dag import fold
from .codegen_support import Printer

ONE = "1.0"


@dataclass
class _Node:
    value: str                                        # C expression of the value (a name or literal)
    tan: dict[int, str] = field(default_factory=dict)  # input index → C expression of ∂value/∂input


def _times(a: str, b: str) -> str:
    if a == ONE:
        return b
    if b == ONE:
        return a
    return f"{a} * {b}"


class _Program:
    def __init__(self, names: Mapping[sp.Symbol, str], inputs: Sequence[sp.Symbol],
                 defs: Sequence[tuple[sp.Symbol, sp.Expr]], indent: str) -> None:
        self.index = {s: i for i, s in enumerate(inputs)}
        self.defs = dict(defs)
        # the symbols that carry derivatives in a fixed order, intermediates (as defined) then
        # inputs: a set of symbols iterates in an order that changes with the string-hash seed
        self.rank: dict[sp.Basic, int] = {}
        for s in [*self.defs, *inputs]:
            self.rank.setdefault(s, len(self.rank))
        self.names = dict(names)
        for i, (s, _) in enumerate(defs):
            self.names.setdefault(s, f"k_{i}")
        self.pr = Printer(self.names)
        self.lines: list[str] = []
        self.indent = indent
        self.memo: dict[sp.Basic, _Node] = {}
        self.trig: dict[tuple[str, str], str] = {}
        self.count = 0

    def _new(self, expr: str) -> str:
        name = f"v_{self.count}"
        self.count += 1
        self.lines.append(f"{self.indent}const double {name} = {expr};")
        return name

    def _trig(self, fn: str, arg: str) -> str:
        """The name of ``fn(arg)``, computed once: a sine's derivative is the cosine of the same
        argument, which the program often has already (GCC does not merge two calls of ``sin``
        itself, since they may set ``errno``; a sine and a cosine of one argument it computes
        together with ``sincos``)."""
        key = (fn, arg)
        if key not in self.trig:
            self.trig[key] = self._new(f"{fn}({arg})")
        return self.trig[key]

    def _children(self, e: sp.Basic) -> Sequence[sp.Basic]:
        if e in self.defs:
            return [self.defs[e]]
        if e.is_Atom:
            return []
        if isinstance(e, (sp.Add, sp.Mul, sp.sin, sp.cos)) or (isinstance(e, sp.Pow) and e.exp.is_Number):
            return e.args
        # another function: kept whole, its free symbols that carry derivatives first (in rank
        # order, so that the generated text does not depend on the process's hash seed)
        return sorted((s for s in e.free_symbols if s in self.rank), key=self.rank.__getitem__)

    def _combine(self, e: sp.Basic, kids: list[_Node]) -> _Node:
        if e in self.defs:  # a named intermediate: its own name, the definition's derivatives
            name = self.names[e]
            node = kids[0]
            self.lines.append(f"{self.indent}const double {name} = {node.value};")
            return _Node(name, {i: self._new(d) if d != ONE else d for i, d in node.tan.items()})
        if e.is_Atom:
            i = self.index.get(e)
            return _Node(self.pr.doprint(e), {} if i is None else {i: ONE})
        if isinstance(e, sp.Add):
            value = self._new(" + ".join(k.value for k in kids))
            tan: dict[int, list[str]] = {}
            for k in kids:
                for i, d in k.tan.items():
                    tan.setdefault(i, []).append(d)
            return _Node(value, {i: self._new(" + ".join(ds)) for i, ds in tan.items()})
        if isinstance(e, sp.Mul):
            value = self._new(" * ".join(f"({k.value})" for k in kids))
            out: dict[int, list[str]] = {}
            for a, k in enumerate(kids):
                others = [f"({o.value})" for b, o in enumerate(kids) if b != a]
                rest = " * ".join(others) if others else ONE
                for i, d in k.tan.items():
                    out.setdefault(i, []).append(_times(d, rest))
            return _Node(value, {i: self._new(" + ".join(ts)) for i, ts in out.items()})
        if isinstance(e, sp.Pow):
            b, ex = kids[0], e.exp
            value = self._new(self.pr.doprint(sp.Pow(sp.Symbol("_b"), ex)).replace("_b", f"({b.value})"))
            dcoef = self.pr.doprint(ex * sp.Pow(sp.Symbol("_b"), ex - 1)).replace("_b", f"({b.value})")
            return _Node(value, {i: self._new(_times(d, f"({dcoef})")) for i, d in b.tan.items()})
        if isinstance(e, (sp.sin, sp.cos)):
            a = kids[0]
            is_sin = isinstance(e, sp.sin)
            value = self._trig("sin" if is_sin else "cos", a.value)
            if not a.tan:
                return _Node(value, {})
            dcoef = self._trig("cos", a.value) if is_sin else f"(-{self._trig('sin', a.value)})"
            return _Node(value, {i: self._new(_times(d, dcoef)) for i, d in a.tan.items()})
        # any other function (Piecewise, Min, Abs, atan2, …): printed whole, differentiated by
        # sympy in the symbols that carry derivatives (such nodes are small: controllers, limits)
        value = self._new(self.pr.doprint(e))
        out = {}
        for s, k in zip(self._children(e), kids):
            d = sp.diff(e, s)
            if d.has(sp.DiracDelta):
                d = d.replace(sp.DiracDelta, lambda *a: sp.Integer(0))
            if d.has(sp.Heaviside, sp.sign):  # derivatives of Min, Max, Abs: printable branches
                d = d.rewrite(sp.Piecewise)
            if d == 0:
                continue
            coef = self._new(self.pr.doprint(d))
            for i, dk in k.tan.items():
                out.setdefault(i, []).append(_times(dk, coef))
        return _Node(value, {i: self._new(" + ".join(ts)) for i, ts in out.items()})

    def node(self, e: sp.Basic) -> _Node:
        return fold(sp.sympify(e), self._children, self._combine, self.memo)


def jacobian_block(exprs: Sequence[sp.Expr], value_targets: Sequence[str | None],
                   jacobian_target: Callable[[int, int], str], inputs: Sequence[sp.Symbol],
                   names: Mapping[sp.Symbol, str], defs: Sequence[tuple[sp.Symbol, sp.Expr]] = (),
                   indent: str = "    ") -> str:
    """C statements computing ``exprs`` (assigned to ``value_targets``; ``None``: not stored) and
    their non-zero partial derivatives, ``jacobian_target(o, i)`` ← ``∂exprs[o]/∂inputs[i]``.
    The caller zero-fills the Jacobian targets first. ``defs`` are named intermediate quantities
    (in order) that the expressions may use."""
    # sympy's common-subexpression pass first (it also finds shared sub-products and sub-sums,
    # which the DAG alone does not): its intermediates become named definitions, whose small
    # expressions are differentiated node by node
    repl, reduced = sp.cse(list(exprs), symbols=sp.numbered_symbols("c_"), order="none")
    prog = _Program(names, inputs, [*defs, *repl], indent)
    nodes = [prog.node(e) for e in reduced]
    for tgt, nd in zip(value_targets, nodes):
        if tgt is not None:
            prog.lines.append(f"{indent}{tgt} = {nd.value};")
    for o, nd in enumerate(nodes):
        for i, d in nd.tan.items():
            prog.lines.append(f"{indent}{jacobian_target(o, i)} = {d};")
    return "\n".join(prog.lines) + "\n"
