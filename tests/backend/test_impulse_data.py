"""The impact and lock maps are derived in amble.derivation.impact."""

import sympy as sp

from amble.derivation.equations import derive
from amble.derivation.impact import impulse_data
from amble.models import load


def _first_impulsive(system, kind):
    for tr in system.transitions:
        if type(tr.reset).__name__ == kind:
            return tr
    raise AssertionError(kind)


def test_impact_extends_the_base():
    s = load("rimless-wheel")
    tr = _first_impulsive(s, "Impact")
    m = s.modes[tr.source]
    d = impulse_data(m, derive(m), tr.reset, s.modes[tr.target])
    n, dims = len(m.q), m.dims
    assert d.Me.shape == (n + dims, n + dims) and d.Jc.shape == (dims, n + dims)
    assert sp.simplify(d.Me - d.Me.T) == sp.zeros(n + dims, n + dims)
    assert d.Jc[:, n:] == sp.eye(dims)
    assert d.velocity_map.shape == (len(s.modes[tr.target].q), n)


def test_lock_uses_the_constraint_gradient():
    s = load("kneed-biped")
    tr = _first_impulsive(s, "Lock")
    m = s.modes[tr.source]
    eq = derive(m)
    d = impulse_data(m, eq, tr.reset, s.modes[tr.target])
    assert d.Me == eq.M
    c = sp.sympify(tr.reset.constraint)
    assert list(d.Jc) == [sp.diff(c, q) for q in m.q]
    assert d.velocity_map == sp.Matrix(d.q_new).jacobian(m.q)
