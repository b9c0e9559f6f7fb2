"""Printing sympy expressions as C statements: the pieces every generated kernel shares.

Coordinates are read from the state array ``x`` (``x[i]`` = qᵢ, ``x[n+i]`` = q̇ᵢ), parameters
from ``p`` and time from ``t`` (:func:`symbol_names`); :func:`block` assigns expressions to C
targets after one common-subexpression pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from sympy.printing.c import C99CodePrinter

from ..derivation.equations import Equations
from ..modelling.model import Model, t


class Printer(C99CodePrinter):
    """C99 printer mapping symbols to array reads and avoiding pow() for small integer powers."""

    def __init__(self, names: dict[sp.Symbol, str]) -> None:
        super().__init__()
        self._names = names

    def _print_Symbol(self, expr: sp.Symbol) -> str:
        name = self._names.get(expr)
        return name if name is not None else super()._print_Symbol(expr)

    _print_Dummy = _print_Symbol

    def _print_Pow(self, expr: sp.Pow) -> str:
        base, e = expr.base, expr.exp
        if e.is_Integer and 2 <= int(e) <= 4:
            b = self.parenthesize(base, 100)
            return "(" + "*".join([b] * int(e)) + ")"
        if e == -1:
            return f"(1.0/{self.parenthesize(base, 100)})"
        return super()._print_Pow(expr)


@dataclass
class ModeInfo:
    """A mode of the system being generated: its model, derived equations and index."""

    model: Model
    equations: Equations
    index: int


def symbol_names(model: Model, params: list[str]) -> dict[sp.Symbol, str]:
    """C names of a mode's symbols: ``t``, ``x[i]`` for the state, ``p[j]`` for parameters."""
    n = len(model.q)
    names: dict[sp.Symbol, str] = {t: "t"}
    for i, s in enumerate(model.q):
        names[s] = f"x[{i}]"
    for i, s in enumerate(model.qd):
        names[s] = f"x[{n + i}]"
    for s in model.params:
        names[s] = f"p[{params.index(str(s))}]"
    return names


def block(targets: list[str], exprs: list[sp.Expr], names: dict[sp.Symbol, str], indent: str = "    ",
          prelude: str = "") -> str:
    """C statements assigning ``exprs`` to ``targets`` with shared subexpressions (after
    ``prelude``, the statements of named intermediate quantities the expressions may use)."""
    if not exprs:
        return ""
    repl, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("c_"), order="none")
    pr = Printer(names)
    lines = [prelude] if prelude else []
    lines += [f"{indent}const double {pr.doprint(s)} = {pr.doprint(e)};" for s, e in repl]
    lines += [f"{indent}{tgt} = {pr.doprint(e)};" for tgt, e in zip(targets, reduced)]
    return "\n".join(lines) + "\n"


def bool_expr(expr: sp.Basic, names: dict[sp.Symbol, str]) -> str:
    """A sympy boolean as a C expression."""
    return Printer(names).doprint(expr)
