"""Code generation's operation count: sympy's number, in time linear in the expression graph."""

import sympy as sp

from amble.backend import codegen_support
from amble.backend.codegen_support import count_ops


def test_count_ops_is_sympys_number():
    x, y = sp.symbols("x y")
    exprs = [-x - y, -x + y, x - 2 * y, -sp.Rational(1, 3) * x, 1 / x, 2 / x, -2 / (x * y), x ** -2, sp.exp(x),
             sp.Max(x, y, 1), sp.sqrt(x), sp.Piecewise((x, x > 0), (y, True)), -x * y / (x + y), sp.sin(x) * y]
    for e in exprs:
        assert count_ops([e]) == sp.count_ops(e), e


def test_count_ops_visits_each_shared_subexpression_once(monkeypatch):
    # a chain of 60 nested sums, each using the one before twice: 2^60 uses as a tree, 60 nodes as a graph
    x = sp.Symbol("x")
    e = x
    for k in range(60):
        e = sp.Mul(e, sp.Add(e, k + 1, evaluate=False), evaluate=False)
    visits = []
    own = codegen_support._own_ops
    monkeypatch.setattr(codegen_support, "_own_ops", lambda a: visits.append(a) or own(a))
    n = count_ops([e])
    assert n > 2 ** 59  # the tree's count
    assert len(visits) <= 3 * 60 + 5  # each distinct node once
