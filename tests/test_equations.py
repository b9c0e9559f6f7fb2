"""Derived equations against hand derivations and the thesis (Eq. 17–19)."""

import sympy as sp
from chains import pendulum_chain

from amble import Model, derive


def test_compass_gait_matches_thesis_eq_17_to_19(compass):
    # Convention: q = (θ1, θ2) = (stance, swing), both measured from the vertical, foot → hip,
    # clockwise (downhill) positive, as in thesis Eq. 6. Thesis Eq. 17–19 write a for the
    # hip-to-leg-mass distance and b for the foot-to-leg-mass distance (the model's a and b).
    # Eq. 18 prints C without its velocities; the standard form is C12 = −m l a sin(θ1−θ2) θ̇2,
    # C21 = m l a sin(θ1−θ2) θ̇1 (the thesis' own MATLAB listing has them), so C q̇ is compared.
    m = compass.modes["compass-gait"]
    eq = derive(m)
    th1, th2 = m.q
    d1, d2 = m.qd
    mh, ml, a, b, g = (m.symbol(n) for n in ("mh", "m", "a", "b", "g"))
    l = a + b
    M = sp.Matrix([[mh * l**2 + ml * b**2 + ml * l**2, -ml * l * a * sp.cos(th1 - th2)],
                   [-ml * l * a * sp.cos(th1 - th2), ml * a**2]])
    C = sp.Matrix([[0, -ml * l * a * sp.sin(th1 - th2) * d2], [ml * l * a * sp.sin(th1 - th2) * d1, 0]])
    G = sp.Matrix([-g * (ml * b + ml * l + mh * l) * sp.sin(th1), ml * a * g * sp.sin(th2)])
    assert sp.simplify(eq.M - M) == sp.zeros(2, 2)
    assert sp.simplify(eq.coriolis - C * sp.Matrix([d1, d2])) == sp.zeros(2, 1)
    assert sp.simplify(eq.G - G) == sp.zeros(2, 1)
    assert sp.simplify(eq.h - (C * sp.Matrix([d1, d2]) + G)) == sp.zeros(2, 1)


def _double_pendulum():
    m = Model("double-pendulum")
    q1, q2 = m.coordinates("q1 q2")
    m1, m2, l1, l2, g = m.parameters(m1=1.0, m2=2.0, l1=0.7, l2=0.4, g=9.81)
    p1 = m.point("p1", l1 * sp.Matrix([sp.sin(q1), -sp.cos(q1)]), mass=m1)
    m.point("p2", p1 + l2 * sp.Matrix([sp.sin(q2), -sp.cos(q2)]), mass=m2)
    m.gravity(g)
    return m


def test_double_pendulum_matches_hand_derivation():
    # By hand (absolute angles from the downward vertical, point masses at the link ends):
    #   M = [[(m1+m2) l1², m2 l1 l2 cos(q1−q2)], [m2 l1 l2 cos(q1−q2), m2 l2²]]
    #   h = [ m2 l1 l2 sin(q1−q2) q̇2² + (m1+m2) g l1 sin q1,
    #        −m2 l1 l2 sin(q1−q2) q̇1² + m2 g l2 sin q2 ]
    m = _double_pendulum()
    eq = derive(m)
    q1, q2 = m.q
    d1, d2 = m.qd
    m1, m2, l1, l2, g = (m.symbol(n) for n in ("m1", "m2", "l1", "l2", "g"))
    c, s = sp.cos(q1 - q2), sp.sin(q1 - q2)
    M = sp.Matrix([[(m1 + m2) * l1**2, m2 * l1 * l2 * c], [m2 * l1 * l2 * c, m2 * l2**2]])
    h = sp.Matrix([m2 * l1 * l2 * s * d2**2 + (m1 + m2) * g * l1 * sp.sin(q1),
                   -m2 * l1 * l2 * s * d1**2 + m2 * g * l2 * sp.sin(q2)])
    assert sp.simplify(eq.M - M) == sp.zeros(2, 2)
    assert sp.simplify(eq.h - h) == sp.zeros(2, 1)


def test_energies_written_outright_give_the_same_equations():
    a = _double_pendulum()
    b = Model("double-pendulum-kv")
    q1, q2 = b.coordinates("q1 q2")
    m1, m2, l1, l2, g = b.parameters(m1=1.0, m2=2.0, l1=0.7, l2=0.4, g=9.81)
    x1, z1 = l1 * sp.sin(q1), -l1 * sp.cos(q1)
    x2, z2 = x1 + l2 * sp.sin(q2), z1 - l2 * sp.cos(q2)
    dt = b.dt
    b.K = sp.Rational(1, 2) * (m1 * (dt(x1) ** 2 + dt(z1) ** 2) + m2 * (dt(x2) ** 2 + dt(z2) ** 2))
    b.V = g * (m1 * z1 + m2 * z2)
    ea, eb = derive(a), derive(b)
    assert sp.simplify(ea.M - eb.M) == sp.zeros(2, 2)
    assert sp.simplify(ea.h - eb.h) == sp.zeros(2, 1)
    c = Model("double-pendulum-l")
    c.coordinates("q1 q2")
    c.parameters(m1=1.0, m2=2.0, l1=0.7, l2=0.4, g=9.81)
    c.L = b.K - b.V
    ec = derive(c)
    assert sp.simplify(ea.M - ec.M) == sp.zeros(2, 2)
    assert sp.simplify(ea.h - ec.h) == sp.zeros(2, 1)


def test_operation_count_grows_polynomially():
    ops = {n: derive(pendulum_chain(n)).count_ops() for n in (3, 6, 12)}
    # M has n² entries of O(n) terms: cubic growth at most (doubling n ≤ 8× + slack);
    # SymPy's own LagrangesMethod already needs millions of operations at n = 6.
    assert ops[6] <= 9 * ops[3]
    assert ops[12] <= 9 * ops[6]
    assert ops[6] < 2000


def test_piecewise_force_and_latex():
    m = Model("forced")
    (q,) = m.coordinates("q")
    (k,) = m.parameters(k=2.0)
    m.point("p", (q, 0), mass=1)
    m.force([sp.Piecewise((-k * q, q > 0), (0, True))])
    eq = derive(m)
    assert eq.Gamma[0].subs({q: 1.0, k: 2.0}) == -2.0
    assert eq.Gamma[0].subs({q: -1.0, k: 2.0}) == 0
    assert "\\ddot" in eq.latex()


def test_body_inertia_of_a_3d_body():
    # A body turning about z by q then tilting about its x axis by r (R = Rz(q) Rx(r)), principal
    # inertias (A, B, C): by hand ω_body = (ṙ, q̇ sin r, q̇ cos r), so
    # K = ½ (A ṙ² + B q̇² sin² r + C q̇² cos² r) and M = diag(B sin² r + C cos² r, A).
    m = Model("top", dims=3)
    q, r = m.coordinates("q r")
    A, B, C = m.parameters(A=1.0, B=2.0, C=3.0)
    Rz = sp.Matrix([[sp.cos(q), -sp.sin(q), 0], [sp.sin(q), sp.cos(q), 0], [0, 0, 1]])
    Rx = sp.Matrix([[1, 0, 0], [0, sp.cos(r), -sp.sin(r)], [0, sp.sin(r), sp.cos(r)]])
    m.body_inertia(Rz * Rx, sp.diag(A, B, C))
    eq = derive(m)
    expected = sp.Matrix([[B * sp.sin(r) ** 2 + C * sp.cos(r) ** 2, 0], [0, A]])
    assert sp.simplify(eq.M - expected) == sp.zeros(2, 2)


def test_constrained_model_equals_the_model_written_with_the_constraint():
    # A double pendulum with both links locked together is a single rigid pendulum: deriving the
    # constrained copy must give the same equations as writing the rigid pendulum directly, and a
    # torque on the eliminated angle must act on the remaining one (virtual work).
    m = _double_pendulum()
    q1, q2 = m.q
    tau = m.parameter("tau", 1.0)
    m.torque(tau, q2)
    c = m.constrained("rigid", {q2: q1})
    m1, m2, l1, l2, g = (m.symbol(n) for n in ("m1", "m2", "l1", "l2", "g"))
    M = m1 * l1**2 + m2 * (l1 + l2) ** 2
    G = (m1 * l1 + m2 * (l1 + l2)) * g * sp.sin(q1)
    eq = derive(c)
    assert c.q == [q1]
    assert sp.simplify(eq.M[0, 0] - M) == 0
    assert sp.simplify(eq.h[0] - G) == 0
    assert eq.Gamma[0] == tau
