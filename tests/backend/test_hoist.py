"""Parameter-only subexpressions are computed once per call (backend/hoist.py): the rewritten
expressions keep their values (checked by substituting numbers into the original sympy
expressions), and compiled kernels read values that follow every change of the parameters
(checked against closed forms, alternating parameter sets from call to call)."""

import math

import numpy as np
import sympy as sp

from amble import Guard, HybridSystem, Model
from amble.backend.hoist import Hoister
from amble.backend.kernels import compiled
from amble.simulation.engine import Options, run


def _values(exprs, hoister, subs):
    """Numbers of hoisted expressions: hoisted symbols replaced by their expressions first."""
    back = {s: e for s, e in hoister.values}
    return [float(sp.sympify(e).xreplace(back).xreplace(subs)) for e in exprs]


def test_rewrite_keeps_values_and_hoists_maximal_parts():
    m, l, g, k = sp.symbols("m l g k", positive=True)
    q, v = sp.symbols("q v", real=True)
    exprs = [2 * m * l * sp.cos(q),                       # the factor 2·m·l is one value
             g * m + g * l + k * q,                       # the sum g·m + g·l is one value
             m * l**2 * sp.sin(q) + m * l**2 * v**2,     # equal parts share one slot
             sp.cos(g) * sp.sin(q) + sp.Piecewise((k * m, q > l * m), (0, True)),
             m * sp.cos(q) + l * sp.cos(q) + v]           # m·cos q + l·cos q → (m + l)·cos q
    h = Hoister({m, l, g, k})
    out = h(exprs)
    subs = {m: 1.7, l: 0.9, g: 9.81, k: 3.1, q: 0.4, v: -1.3}
    assert np.allclose(_values(out, h, subs), [float(e.xreplace(subs)) for e in exprs], rtol=1e-14)
    # no parameter is left outside a hoisted value except where it stands alone next to a variable
    assert out[0].free_symbols == {q, h.values[0][0]} and len(out[0].args) == 2
    assert (g * m + g * l) in {e for _, e in h.values}
    assert len([s for s in out[4].free_symbols if s in h.names]) == 1
    n_slots = len(h.values)
    h([m * l**2 * sp.sin(q)])  # already hoisted: no new slot
    assert len(h.values) == n_slots
    # disabled: the expressions come back unchanged
    assert Hoister({m, l, g, k}, enabled=False)(exprs) == exprs


def test_a_graph_without_parameters_comes_back_as_it_was():
    # an unevaluated shared graph (a tree's positions) is not rebuilt: rebuilding evaluates,
    # which re-flattens the graph and asks sympy for signs of all of it
    m, l = sp.symbols("m l", positive=True)
    q, v = sp.symbols("q v", real=True)
    e = q
    for _ in range(30):
        half_cos = sp.Mul(sp.Float(0.5), sp.cos(e, evaluate=False), evaluate=False)
        e = sp.Add(half_cos, sp.Mul(-1, 2, e, evaluate=False), evaluate=False)
    h = Hoister({m, l})
    assert h.one(e) is e and not h.values
    # a relation is rebuilt unevaluated: sympy would decide (q + m·l)² + 1 > 0 to True
    rel = sp.StrictGreaterThan(sp.Pow(q + m * l, 2) + 1, 0, evaluate=False)
    out = h.one(rel)
    assert isinstance(out, sp.StrictGreaterThan) and len(h.values) == 1
    assert h.values[0][1] == m * l
    back = {s: x for s, x in h.values}
    subs = {m: 1.3, l: 0.7, q: -0.4}
    assert math.isclose(float(out.lhs.xreplace(back).xreplace(subs)), float(rel.lhs.xreplace(subs)), rel_tol=1e-15)


def _pendulum():
    """A point mass on a massless rod with viscous damping; a terminal guard th = a·cos(b)
    (rising): parameter-only products and a parameter's cosine for the prelude."""
    m = Model("hoist_pendulum")
    (th,) = m.coordinates(["th"])
    mass, length, g, c, a, b = m.parameters(mass=1.0, length=1.0, g=9.81, c=0.0, a=0.1, b=0.3)
    m.point("bob", sp.Matrix([length * sp.sin(th), -length * sp.cos(th)]), mass=mass)
    m.gravity(g)
    m.torque(-c * m.dot(th), th)
    s = HybridSystem(m.name, m)
    s.terminal("reached", m.name, Guard(th - a * sp.cos(b), 1), status="reached")
    return s


def test_compiled_kernels_follow_parameter_changes():
    # M = m l² is parameter-only: its pivot and reciprocal come from the prelude too
    k = compiled(_pendulum())
    src = k.path.with_suffix(".c").read_text()
    assert "p[NPARAM + " in src and "NHOIST" in src
    x = np.array([0.7, -0.4])
    for mass, length, g, c, a, b in [(1.0, 1.0, 9.81, 0.0, 0.1, 0.3), (2.5, 0.3, 1.6, 0.7, 0.4, 1.2),
                                     (1.0, 1.0, 9.81, 0.0, 0.1, 0.3)]:
        p = np.array([mass, length, g, c, a, b])
        dx = k.rhs(0, 0.0, x, p)
        expect = -g / length * math.sin(x[0]) - c * x[1] / (mass * length**2)
        assert math.isclose(dx[1], expect, rel_tol=1e-13)
        assert math.isclose(k.guards(0, 0.0, x, p)[0], x[0] - a * math.cos(b), rel_tol=1e-13)


def test_run_reads_the_prelude_of_its_own_parameters():
    # small oscillations th = A sin(ωt), ω = √(g/l): the guard at th = A/2 fires at asin(1/2)/ω,
    # for parameter sets in turn (a stale hoisted length or cos(b) would move it)
    k = compiled(_pendulum())
    amp, g = 1e-3, 9.81
    for length, b in ((0.5, 0.3), (2.0, 1.1), (0.5, 0.3)):
        omega = math.sqrt(g / length)
        a = 0.5 * amp / math.cos(b)
        p = np.array([1.0, length, g, 0.0, a, b])
        r = run(k, p, 0, np.array([0.0, amp * omega]), t_end=10.0, opts=Options(rtol=1e-12, atol=1e-15))
        assert r.status == "reached"
        assert math.isclose(r.t, math.asin(0.5) / omega, rel_tol=1e-6)
