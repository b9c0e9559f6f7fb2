"""Printing sympy expressions as C statements: the pieces every generated kernel shares.

Coordinates are read from the state array ``x`` (``x[i]`` = qᵢ, ``x[n+i]`` = q̇ᵢ), parameters
from ``p`` and time from ``t`` (:func:`symbol_names`); :func:`block` assigns expressions to C
targets after one common-subexpression pass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import sympy as sp
from sympy.concrete.summations import Sum
from sympy.core.function import Derivative, _coeff_isneg
from sympy.core.operations import LatticeOp
from sympy.integrals.integrals import Integral
from sympy.printing.c import C99CodePrinter
from sympy.simplify.radsimp import fraction

from ..derivation.equations import Equations
from ..modelling.dag import fold
from ..modelling.model import Model, t


class Printer(C99CodePrinter):
    """C99 printer mapping symbols to array reads and avoiding pow() for small integer powers.

    Terms and factors are printed in the order the expression holds them (``order="none"``):
    sympy's default sorts every sum's terms first, which is most of the printing time of a large
    model (2.6× on the 30-DOF humanoid's intermediate quantities) and changes nothing but the order
    of the additions.

    Constants (π, e, √2, 1/π, ...) are printed as their double values, never as the ``M_PI``
    family of macros: those are not C99 (``<math.h>`` declares them only as an extension, which
    ``-std=c99`` turns off), so a reset or guard holding ``sympy.pi`` would not compile."""

    math_macros: dict = {}  # sympy reads this class attribute; empty: no macros

    def __init__(self, names: dict[sp.Symbol, str]) -> None:
        super().__init__(settings={"order": "none"})
        self._names = names

    def doprint(self, expr: Any, assign_to: Any = None) -> str:
        """C text of ``expr``: sums, products, integer and half powers, sin and cos of numbers and
        symbols directly (:func:`_c_text`), anything else by sympy's C99 printer."""
        if assign_to is not None or not isinstance(expr, sp.Basic):
            return super().doprint(expr, assign_to)
        return _standalone(_c_text(self, expr))

    def _print_Symbol(self, expr: sp.Symbol) -> str:
        name = self._names.get(expr)
        return name if name is not None else super()._print_Symbol(expr)

    _print_Dummy = _print_Symbol

    def _print_NumberSymbol(self, expr: sp.NumberSymbol) -> str:
        return repr(float(expr))  # the nearest double: 17 significant digits read back exactly

    def _print_Pow(self, expr: sp.Pow) -> str:
        base, e = expr.base, expr.exp
        if e.is_Integer and 2 <= int(e) <= 4:
            b = self.parenthesize(base, 100)
            return "(" + "*".join([b] * int(e)) + ")"
        if e == -1:
            return f"(1.0/{self.parenthesize(base, 100)})"
        return super()._print_Pow(expr)


# precedence of a printed piece: a sum, a product or quotient, an atom (a name, a call, brackets)
_ADD, _MUL, _ATOM = 1, 2, 3
_CALLS = {sp.sin: "sin", sp.cos: "cos"}


def _standalone(piece: tuple[str, int, bool]) -> str:
    text, _, neg = piece
    return "-" + text if neg else text


def _operand(piece: tuple[str, int, bool], need: int) -> str:
    """A printed piece as an operand of an operator of precedence ``need`` (bracketed if it binds
    less tightly, or is negated)."""
    text, prec, neg = piece
    if neg:
        return f"(-{text})" if need > _ADD or prec <= _ADD else "-" + text
    return f"({text})" if prec < need else text


def _c_text(pr: Printer, e: sp.Basic) -> tuple[str, int, bool]:
    """``(text, precedence, negated)`` of ``e`` in C: the value is ``-text`` if ``negated``.

    Why not sympy's printer: its products ask sympy for the sign of every factor and build new
    negated expressions to print them, which makes printing the largest part of generating a big
    model's code. This prints the expression as it stands — each operation in the order and
    grouping of the graph (a nested sum keeps its brackets) — and hands what it does not know
    (other functions, piecewise, relations, constants such as π) to sympy's printer whole."""
    if e.is_Symbol:
        return pr._print_Symbol(e), _ATOM, False
    if e.is_Integer:
        v = int(e)
        if abs(v) < 2 ** 31:
            return str(abs(v)), _ATOM, v < 0
    elif e.is_Rational:
        p, q = int(e.p), int(e.q)
        if abs(p) < 2 ** 53 and q < 2 ** 53:
            return f"{abs(p)}.0/{q}.0", _MUL, p < 0
    elif e.is_Float:
        v = float(e)
        if math.isfinite(v):
            return repr(abs(v)), _ATOM, v < 0 or (v == 0 and math.copysign(1.0, v) < 0)
    elif isinstance(e, sp.Add):
        parts = []
        for k, a in enumerate(e.args):
            text, prec, neg = _c_text(pr, a)
            text = f"({text})" if prec <= _ADD and (neg or k > 0) else text  # the graph's grouping
            parts.append((" - " if neg else " + ") + text if k else ("-" + text if neg else text))
        return "".join(parts), _ADD, False
    elif isinstance(e, sp.Mul):
        num, den, neg = [], [], False
        for a in e.args:
            if a.is_Pow and a.exp.is_Integer and -4 <= int(a.exp) <= -1:
                b = _operand(_c_text(pr, a.base), _ATOM)
                den.append("*".join([b] * -int(a.exp)))
                continue
            text, prec, n = _c_text(pr, a)
            if a.is_Number and text == "1" and not num:
                neg ^= n  # a coefficient ±1 is a sign
                continue
            neg ^= n
            num.append(f"({text})" if prec < _MUL or (prec == _MUL and a.is_Rational) else text)
        out = "*".join(num) if num else "1.0"
        if den:
            d = den[0] if len(den) == 1 and "*" not in den[0] else "(" + "*".join(den) + ")"
            out = f"{out}/{d}" if num else f"1.0/{d}"
        return out, _MUL, neg
    elif e.is_Pow:
        b, x = e.args
        if x.is_Integer and 1 <= int(x) <= 4:
            base = _operand(_c_text(pr, b), _ATOM)
            return ("(" + "*".join([base] * int(x)) + ")") if int(x) > 1 else base, _ATOM, False
        if x.is_Integer and -4 <= int(x) <= -1:
            base = _operand(_c_text(pr, b), _ATOM)
            d = base if int(x) == -1 else "(" + "*".join([base] * -int(x)) + ")"
            return f"1.0/{d}", _MUL, False
        if x == sp.S.Half:
            return f"sqrt({_standalone(_c_text(pr, b))})", _ATOM, False
    elif type(e) in _CALLS:
        return f"{_CALLS[type(e)]}({_standalone(_c_text(pr, e.args[0]))})", _ATOM, False
    return f"({C99CodePrinter.doprint(pr, e)})", _ATOM, False


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
          prelude: str = "", shared: bool = False) -> str:
    """C statements assigning ``exprs`` to ``targets`` with shared subexpressions (after
    ``prelude``, the statements of named intermediate quantities the expressions may use).

    ``shared``: the expressions are graphs whose common parts are already shared (a rigid-body
    tree's kinematics and energies, expanded from its named intermediate quantities): each
    subexpression used more than once becomes a temporary as it stands (:func:`shared_cse`),
    instead of ``sympy.cse`` searching again for what the recursion built once. Expressions that
    are such graphs (:func:`is_shared_graph`: a tree's guards and relabelling) are treated so
    without being told."""
    if not exprs:
        return ""
    if shared or is_shared_graph(exprs):
        repl, reduced = shared_cse(exprs)
    else:
        repl, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("c_"), order="none")
    pr = Printer(names)
    lines = [prelude] if prelude else []
    lines += [f"{indent}const double {pr.doprint(s)} = {pr.doprint(e)};" for s, e in repl]
    lines += [f"{indent}{tgt} = {pr.doprint(e)};" for tgt, e in zip(targets, reduced)]
    return "\n".join(lines) + "\n"


#: Distinct compound subexpressions from which :func:`is_shared_graph` looks at the sharing.
SHARED_MIN_NODES = 1000


def is_shared_graph(exprs: list[Any]) -> bool:
    """Whether ``exprs`` are large graphs whose common parts are shared already: at least
    :data:`SHARED_MIN_NODES` distinct compound subexpressions, written out as trees more than
    four times as many. A rigid-body tree's positions, expanded from its recursion, are such
    graphs (the 12-DOF biped's footfall guard: 30× as large as a tree); ``sympy.cse`` walks and
    rebuilds them as trees, evaluated, and takes minutes for what the graph shares already.
    Linear in the number of distinct subexpressions."""
    size: dict[int, int] = {}
    stack = [sp.sympify(e) for e in exprs]
    while stack:  # post-order by identity: the tree size of each node, each node once
        e = stack[-1]
        if id(e) in size or e.is_Atom:
            stack.pop()
            continue
        todo = [a for a in e.args if not a.is_Atom and id(a) not in size]
        if todo:
            stack.extend(todo)
            continue
        size[id(e)] = 1 + sum(size.get(id(a), 1) for a in e.args)
        stack.pop()
    if len(size) < SHARED_MIN_NODES:
        return False
    total = sum(size.get(id(e), 1) for e in map(sp.sympify, exprs))
    return total > 4 * len(size)


def shared_cse(exprs: list[sp.Expr]) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """Common subexpressions of expression graphs, as ``sympy.cse`` returns them (temporaries in
    an order where each comes after those it uses, then the reduced expressions): every
    non-atomic subexpression reached from more than one place is named once. Linear in the
    number of distinct subexpressions — no search for common parts of sums or products beyond
    those the graph already shares, which is what a recursion over a tree leaves none of."""
    exprs = [sp.sympify(e) for e in exprs]
    uses: dict[sp.Basic, int] = {}
    stack = list(exprs)
    while stack:  # how often each distinct subexpression is an argument (or a root)
        e = stack.pop()
        if e.is_Atom:
            continue
        n = uses.get(e, 0)
        uses[e] = n + 1
        if n == 0:
            stack.extend(e.args)
    names = sp.numbered_symbols("c_", cls=sp.Dummy)
    repl: list[tuple[sp.Symbol, sp.Expr]] = []

    def combine(e: sp.Basic, args: list) -> sp.Basic:
        if e.is_Atom:
            return e
        if all(a is b for a, b in zip(args, e.args)):
            r = e
        elif isinstance(e, (sp.Add, sp.Mul, sp.Pow, sp.Function)):
            # as built: no re-flattening of shared parts, and no questions to sympy about the
            # signs of a graph (an evaluated power of a sum asks them: seconds per power)
            r = e.func(*args, evaluate=False)
        else:
            r = e.func(*args)
        if uses.get(e, 0) > 1:
            s = next(names)
            repl.append((s, r))
            return s
        return r

    memo: dict = {}
    reduced = [fold(e, lambda x: () if x.is_Atom else x.args, combine, memo) for e in exprs]
    return repl, reduced


def bool_expr(expr: sp.Basic, names: dict[sp.Symbol, str]) -> str:
    """A sympy boolean as a C expression."""
    return Printer(names).doprint(expr)


def _own_ops(a: sp.Basic) -> tuple[int, tuple]:
    """The operations ``sympy.count_ops`` charges to ``a`` itself, and the expressions it goes on
    to count (its arguments, or the numerator, denominator or negation it splits ``a`` into):
    the body of ``count_ops``' work list, one item."""
    if a.is_Rational:
        return (0, ()) if a is sp.S.One else (int(a.p < 0) + int(a.q != 1), ())
    w = 0
    if a.is_Mul:
        if _coeff_isneg(a):
            w += 1
            a = a.as_two_terms()[1] if a.args[0] is sp.S.NegativeOne else -a
        num, den = fraction(a)
        if num.is_Integer:
            return w + 1 + int(bool(num < 0)), (den,)
        if den is not sp.S.One:
            return w + 1, ((num,) if den.is_Integer else (den, num))
    elif a.is_Add:
        negs = [_coeff_isneg(x) for x in a.args]
        # one ADD or SUB between terms; -x - y is a NEG more (-x + y is a SUB instead of an ADD)
        return len(a.args) - 1 + int(all(negs)), tuple(-x if ng else x for x, ng in zip(a.args, negs))
    if a.is_Pow and a.exp is sp.S.NegativeOne:
        return w + 1, (a.base,)
    if a == sp.S.Exp1:
        return w + 1, ()
    if a.is_Pow and a.base == sp.S.Exp1:
        return w + 1, (a.exp,)
    if a.is_Mul or isinstance(a, LatticeOp):
        w += len(a.args) - 1
    elif a.args and (a.is_Pow or a.is_Function or isinstance(a, (Derivative, Integral, Sum))):
        w += 1
    return w, (() if a.is_Symbol else a.args)


def count_ops(exprs: list[Any], memo: dict | None = None) -> int:
    """``sum(sympy.count_ops(e) for e in exprs)``, the same number, with each distinct
    subexpression counted once and its count reused at every further use (``memo``: expression →
    operations as a tree). ``sympy.count_ops`` walks a shared subexpression again at every use:
    on expressions that share their parts (a Lagrangian's derivatives, a chain's kinematics) that
    is a walk of the tree they spell out, exponentially larger than the graph. Linear in the
    number of distinct subexpressions."""
    memo = {} if memo is None else memo
    own: dict[sp.Basic, tuple[int, tuple]] = {}
    total = 0
    for e in exprs:
        e = sp.sympify(e)
        if not isinstance(e, sp.Expr) or e.is_Relational:
            total += sp.count_ops(e)
            continue
        stack = [e]
        while stack:  # post-order: an item's count once those of the items it goes on to are known
            a = stack[-1]
            if a in memo:
                stack.pop()
                continue
            if a not in own:
                own[a] = _own_ops(a)
            w, kids = own[a]
            todo = [k for k in kids if k not in memo]
            if todo:
                stack.extend(todo)
                continue
            memo[a] = w + sum(memo[k] for k in kids)
            stack.pop()
        total += memo[e]
    return total
