"""Parameter-only subexpressions, computed once per call of the library instead of once per use.

Parameters are run-time inputs of a compiled system, so a product such as ``m·l²`` or
``cos(slope)`` is the same number at every right-hand side, guard and reset of a run — but
written inline it is recomputed at every evaluation (hundreds per walking step). A
:class:`Hoister` replaces every *maximal* parameter-only subexpression of the kernels' expressions
by a symbol of its own, and emits the C function that computes them all once:

* ``amble_params_prelude(p, q)`` copies the ``NPARAM`` parameters ``p`` to ``q`` and writes the
  ``NHOIST`` hoisted values after them, ``q[NPARAM + j]``;
* every exported entry point of the library (``hybrid.c``) starts with ``AMBLE_PARAMS(p)``, which
  fills such an array on its stack and continues with it in place of ``p``. The internal kernels
  therefore always receive ``NPARAM + NHOIST`` values: raw parameters first (the derivative
  kernels differentiate with respect to those and read them unchanged), hoisted values after.

Python passes and sees ``NPARAM`` parameters only, as before: nothing of the prelude crosses the
interface, and changing a parameter between calls can never leave a stale hoisted value behind.

"Maximal" matters for sums and products, which sympy flattens: of ``2·m·l·cos(q)`` the factor
``2·m·l`` is one hoisted value, of ``g·m + g·M + k·q`` the part ``g·m + g·M``. Only real-valued
expressions are hoisted (never a relation, a boolean or a ``Piecewise`` pair), and never a lone
symbol or number (nothing would be saved).
"""

from __future__ import annotations

from typing import Any

import sympy as sp
from sympy.core.relational import Relational

from ..modelling.dag import fold


def _children(e: Any) -> tuple:
    return () if not isinstance(e, sp.Basic) or e.is_Atom else e.args


def _hoistable(e: Any) -> bool:
    """A real-valued compound expression (a C ``double``), worth a slot."""
    return isinstance(e, sp.Expr) and not e.is_Atom and not isinstance(e, sp.Piecewise)


class Hoister:
    """The hoisted values of one translation unit (shared by all its kernels; equal expressions
    share one slot). ``params``: the parameter symbols of every mode (anything else — state,
    time, rates, intermediate quantities — is a variable). ``enabled=False`` hoists nothing: the
    code every kernel had before, for measuring what hoisting saves."""

    def __init__(self, params: set[sp.Symbol], enabled: bool = True) -> None:
        self.params = frozenset(params)
        self.enabled = enabled  # False: nothing is hoisted (the prelude only copies p)
        self._slot: dict[sp.Expr, sp.Symbol] = {}
        self.values: list[tuple[sp.Symbol, sp.Expr]] = []  # (symbol, expression) in slot order
        self.names: dict[sp.Symbol, str] = {}  # symbol → its C read, p[NPARAM + j]
        self._memo: dict = {}
        self._expr: dict[sp.Symbol, sp.Expr] = {}  # hoisted symbol → its expression
        self._flag: dict[Any, bool] = {}  # rewritten nodes: parameter-only or not
        self._kept: set[int] = set()  # ids of mixed nodes that came back as they were

    def _take(self, e: sp.Expr) -> sp.Expr:
        """The hoisted symbol of ``e`` (a new slot unless an equal expression has one). A negated
        parameter stays inline: ``-p`` costs nothing in a sum."""
        if e.is_Mul and len(e.args) == 2 and e.args[0] == -1 and e.args[1].is_Atom:
            return e
        s = self._slot.get(e)
        if s is None:
            j = len(self.values)
            s = sp.Dummy(f"P{j}", real=True)
            self._slot[e] = s
            self._expr[s] = e
            self.values.append((s, e))
            self.names[s] = f"p[NPARAM + {j}]"
        return s

    def _const(self, f: Any) -> bool:
        """Whether a factor of a rewritten term is parameter-only (a hoisted symbol, a parameter,
        a number, or a node this pass has marked so)."""
        if f in self._expr or f in self.params or getattr(f, "is_number", False):
            return True
        return self._flag.get(f, False)

    def _collect(self, kids: list[tuple[Any, bool]]) -> list[Any]:
        """Terms of a sum with equal non-constant parts merged: ``a·u + b·u → (a + b)·u`` with
        ``a + b`` hoisted (sympy expands, so mass matrices are full of ``m₁·u + m₂·u + …``)."""
        groups: dict[Any, list[Any]] = {}
        const: list[Any] = []
        alone: dict[Any, Any] = {}  # the term as it came, for a part no other term shares
        out_plain: list[Any] = []  # terms without a parameter: left as they are
        for r, c in kids:
            if c:
                const.append(r)
                continue
            fs = sp.Mul.make_args(r)
            cf = [f for f in fs if self._const(f)]
            if all(f.is_Number for f in cf):  # nothing to hoist: numbers are folded by sympy (or C)
                out_plain.append(r)
                continue
            vf = [f for f in fs if not self._const(f)]
            var = sp.Mul(*vf)
            groups.setdefault(var, []).append(sp.Mul(*cf))
            alone[var] = r
        out = []
        for var, coeffs in groups.items():
            if len(coeffs) == 1:
                out.append(alone[var])  # not rebuilt: a shared graph stays shared
                continue
            total = sp.Add(*coeffs).xreplace(self._expr)  # in parameters only: the prelude has no order
            out.append((self._take(total) if _hoistable(total) else total) * var)
        if all(a.is_Number for a in const):
            pass
        elif len(const) >= 2:
            part = sp.Add(*const)
            const = [self._take(part) if _hoistable(part) else part]
        else:
            const = [self._take(a) if _hoistable(a) else a for a in const]
        return const + out + out_plain

    def _same(self, new: list[Any], kids: list[tuple[Any, bool]], e: sp.Basic) -> bool:
        """Whether ``new`` holds ``e``'s arguments as they were (in any order): each the very
        argument, or the rewritten form of one that came back unchanged (the fold's memo hands
        back the first of equal subexpressions it met, so "unchanged" is an equal object)."""
        if len(new) != len(e.args):
            return False
        stand = {id(r): a for (r, _), a in zip(kids, e.args)
                 if r is a or id(r) in self._kept or (a.is_Atom and r == a)}
        return {id(stand.get(id(x), x)) for x in new} == {id(a) for a in e.args}

    def _keep(self, e: sp.Basic) -> sp.Basic:
        self._kept.add(id(e))
        return e

    def _combine(self, e: Any, kids: list[tuple[Any, bool]]) -> tuple[Any, bool]:
        """(rewritten node, whether it is parameter-only). A parameter-only node is left whole for
        its parent to hoist; a mixed node hoists its parameter-only compound children."""
        if not kids:
            if isinstance(e, sp.Symbol):
                return e, e in self.params
            return e, bool(getattr(e, "is_number", False))
        if all(c for _, c in kids):
            return e, isinstance(e, sp.Expr)
        # A node whose arguments come back as they were is kept, not rebuilt: rebuilding
        # evaluates, and an evaluated sum, power, function or relation of a rigid-body tree's
        # shared graph re-flattens it and asks sympy for signs and assumptions of the whole
        # graph (``ahead > margin`` of the 12-DOF walker's footfall: 98 s of its build)
        if isinstance(e, sp.Add):
            terms = self._collect(kids)
            r = self._keep(e) if self._same(terms, kids, e) else sp.Add(*terms)
        elif isinstance(e, sp.Mul):
            const = [a for a, c in kids if c]
            rest = [a for a, c in kids if not c]
            if all(a.is_Number for a in const):  # numbers only: nothing to hoist
                pass
            elif len(const) >= 2:  # the parameter-only part of a flattened product, as one value
                part = e.func(*const)
                const = [self._take(part) if _hoistable(part) else part]
            else:
                const = [self._take(a) if _hoistable(a) else a for a in const]
            r = self._keep(e) if self._same([*const, *rest], kids, e) else e.func(*const, *rest)
        else:
            args = [self._take(a) if c and _hoistable(a) else a for a, c in kids]
            if self._same(args, kids, e):
                r = self._keep(e)
            elif isinstance(e, (Relational, sp.Pow, sp.Function)):
                # only a hoisted value replaced a part: nothing for sympy to evaluate
                r = e.func(*args, evaluate=False)
            else:
                r = e.func(*args)
        self._flag[r] = False
        return r, False

    def __call__(self, exprs: list[Any]) -> list[Any]:
        """``exprs`` with their maximal parameter-only subexpressions replaced by hoisted symbols."""
        if not self.enabled:
            return [sp.sympify(x) for x in exprs]
        out = []
        for x in exprs:
            x = sp.sympify(x)
            r, const = fold(x, _children, self._combine, self._memo)
            out.append(self._take(r) if const and _hoistable(r) else r)
        return out

    def one(self, expr: Any) -> Any:
        """One expression, hoisted (see :meth:`__call__`)."""
        return self([expr])[0]

    def c_code(self, nparam: int, names: dict[sp.Symbol, str], block: Any) -> str:
        """The prelude function and the ``AMBLE_PARAMS`` macro of the entry points, for
        ``nparam`` parameters; ``names`` maps parameter symbols to ``p[i]``; ``block`` is the
        statement printer (targets, exprs, names) → C of the code generator."""
        n = len(self.values)
        out = [f"#define NHOIST {n}\n#define NPFULL (NPARAM + NHOIST)\n",
               "/* parameters, then their parameter-only subexpressions (backend/hoist.py) */\n",
               "static void amble_params_prelude(const double *p, double *q) {\n",
               f"    for (int i = 0; i < {nparam}; ++i) q[i] = p[i];\n"]
        if n:
            out.append(block([f"q[NPARAM + {j}]" for j in range(n)], [e for _, e in self.values], names))
        out.append("}\n")
        # the entry points continue with the full array in place of the caller's parameters
        out.append("#define AMBLE_PARAMS(p) double p##_full_[NPFULL]; amble_params_prelude(p, p##_full_); "
                   "p = p##_full_\n")
        return "".join(out)
