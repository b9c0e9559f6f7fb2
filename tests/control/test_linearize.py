"""linearize(): exact A, B against a closed form and against central differences of the
compiled right-hand side."""

import numpy as np
import pytest

from amble import HybridSystem, Model, R, StateError
from amble.analysis.linearize import linearize
from amble.backend.kernels import compiled


def test_inverted_pendulum_closed_form():
    m = Model("inverted")
    (th,) = m.coordinates("theta")
    m.point("pivot", (0, 0))
    m.point("bob", 0.5 * R(th), mass=2.0, link="pivot")
    m.gravity(9.81)
    m.actuator("motor", on=th)
    A, B = linearize(HybridSystem("inv", m), [0.0, 0.0])
    np.testing.assert_allclose(A, [[0, 1], [9.81 / 0.5, 0]], atol=1e-12)
    np.testing.assert_allclose(B, [[0], [1 / (2.0 * 0.25)]], atol=1e-12)
    with pytest.raises(StateError):
        linearize(HybridSystem("inv", m), [0.0])


def test_double_pendulum_against_finite_differences():
    """The input enters the compiled right-hand side as parameters (u = u0_j), so central
    differences in x and in the parameters check A and B."""
    m = Model("acrobot")
    a, b = m.coordinates("upper lower")
    m.point("pivot", (0, 0))
    elbow = m.point("elbow", 0.6 * R(a), mass=1.5, link="pivot")
    m.point("tip", elbow + 0.4 * R(b), mass=0.8, link="elbow")
    m.add_potential(3.0 * (b - a) ** 2 / 2)
    m.gravity(9.81)
    u1, u2 = m.actuator("shoulder", on=a), m.actuator("elbow_motor", on=b - a)
    p1, p2 = m.parameters(u0_1=0.7, u0_2=-1.3)
    m.control({u1: p1, u2: p2})
    s = HybridSystem("acrobot", m)
    x0 = np.array([0.3, -0.5, 1.1, -0.4])
    A, B = linearize(s, x0, [0.7, -1.3])
    k = compiled(s)
    p = np.array([k.meta["param_defaults"][i] for i in range(len(k.meta["params"]))])
    h = 1e-6
    fd = np.column_stack([(k.rhs(0, 0.0, x0 + h * e, p) - k.rhs(0, 0.0, x0 - h * e, p)) / (2 * h) for e in np.eye(4)])
    np.testing.assert_allclose(A, fd, atol=1e-7)
    cols = []
    for name in ("u0_1", "u0_2"):
        e = np.zeros_like(p)
        e[k.meta["params"].index(name)] = h
        cols.append((k.rhs(0, 0.0, x0, p + e) - k.rhs(0, 0.0, x0, p - e)) / (2 * h))
    np.testing.assert_allclose(B, np.column_stack(cols), atol=1e-7)
