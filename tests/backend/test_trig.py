"""sin² + cos² = 1 inside sums, without expanding: exact pairs collapse, values never change."""

import random

import sympy as sp

from amble.backend.trig import pythagoras

a, b, q, r, m, l = sp.symbols("a b q r m l", real=True)


def test_pairs_collapse():
    assert pythagoras([m * (l**2 * sp.sin(q) ** 2 + l**2 * sp.cos(q) ** 2)]) == [m * l**2]
    # the rest of a pair may hold other squares: indexed under every one of them
    e = sp.cos(a) ** 2 * sp.cos(b) ** 2 * l + sp.sin(a) ** 2 * sp.cos(b) ** 2 * l
    assert pythagoras([e]) == [l * sp.cos(b) ** 2]


def test_nested_pairs_collapse_to_the_end():
    # a direction with two angles (|R3(a, b)|² = 1): one pair's rest pairs with another term
    e = l * sp.sin(a) ** 2 * sp.sin(b) ** 2 + l * sp.sin(b) ** 2 * sp.cos(a) ** 2 + l * sp.cos(b) ** 2
    assert pythagoras([e]) == [l]
    assert pythagoras([m * e + q]) == [m * l + q]


def test_non_pairs_are_left_alone():
    for e in (sp.sin(q) ** 2 + sp.cos(r) ** 2, 2 * sp.sin(q) ** 2 + sp.cos(q) ** 2, sp.sin(q) ** 2 * sp.cos(q) ** 2):
        assert pythagoras([e]) == [e]


def test_values_are_unchanged_on_a_model():
    from amble import derive
    from amble.models import load

    model = next(iter(load("kneed-biped").modes.values()))
    eq = derive(model)
    exprs = [*eq.M, *eq.h]
    new = pythagoras(exprs)
    assert sum(sp.count_ops(e) for e in new) < sum(sp.count_ops(e) for e in exprs)
    rng = random.Random(0)
    syms = set().union(*(e.free_symbols for e in exprs))
    for _ in range(5):
        sub = {s: rng.uniform(-1.5, 1.5) for s in syms}
        for old, e in zip(exprs, new):
            assert abs(float(old.subs(sub)) - float(e.subs(sub))) <= 1e-12 * (1 + abs(float(old.subs(sub))))
