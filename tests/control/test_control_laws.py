"""Control laws written with the model's own dynamics, and saturation — against closed forms and
SciPy."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from amble import HybridSystem, Model, R, simulate


def _double_pendulum():
    m = Model("double-pendulum")
    a, b = m.coordinates("upper lower")
    m.point("pivot", (0, 0))
    elbow = m.point("elbow", 0.6 * R(a), mass=1.5, link="pivot")
    m.point("tip", elbow + 0.4 * R(b), mass=0.8, link="elbow")
    m.gravity(9.81)
    u1 = m.actuator("shoulder", on=a)
    u2 = m.actuator("elbow_motor", on=b - a)
    return m, (a, b), (u1, u2)


def test_computed_torque_is_one_line_and_makes_the_error_linear():
    """u = B⁻¹(M v + h) with v = −k_p q − k_d q̇ gives q̈ = v exactly: each coordinate is a
    critically damped oscillator, q(t) = (q₀ + (q̇₀ + ω q₀) t) e^{−ωt} with ω = 4 rad/s."""
    m, q, u = _double_pendulum()
    M, h = m.mass_and_bias()
    w = 4.0
    v = sp.Matrix([-w**2 * qi - 2 * w * m.dot(qi) for qi in q])
    m.control(dict(zip(u, m.input_matrix().inv() * (M * v + h))))
    tr = simulate(HybridSystem("dp", m), [0.4, -0.3, 0.0, 1.0], t_end=2.0, sample_dt=0.05)
    for name, q0, v0 in (("upper", 0.4, 0.0), ("lower", -0.3, 1.0)):
        exact = (q0 + (v0 + w * q0) * tr.t) * np.exp(-w * tr.t)
        np.testing.assert_allclose(tr.column(name), exact, rtol=0, atol=1e-8)


def test_point_jacobian_and_velocity():
    m, (a, b), _ = _double_pendulum()
    J = m.point_jacobian("tip")
    exact = sp.Matrix([[0.6 * sp.cos(a), 0.4 * sp.cos(b)], [-0.6 * sp.sin(a), -0.4 * sp.sin(b)]])
    assert sp.simplify(J - exact) == sp.zeros(2, 2)
    assert sp.simplify(m.point_velocity("tip") - J * sp.Matrix(m.qd)) == sp.zeros(2, 1)


def test_saturation_clips_at_the_declared_limit():
    """An inverted pendulum pushed with 50 N·m through a 3 N·m actuator follows
    m l² θ̈ = 3 + m g l sin θ (SciPy; R(θ) points up, an inverted pendulum), and the recorded
    input is the clipped one."""
    m = Model("pushed")
    (th,) = m.coordinates("theta")
    m.point("pivot", (0, 0))
    m.point("bob", 0.5 * R(th), mass=1.0, link="pivot")
    m.gravity(9.81)
    u = m.actuator("motor", on=th, limit=3.0)
    m.control({u: 50 * sp.cos(th)}, saturate=True)
    tr = simulate(HybridSystem("pushed", m), [0.0, 0.0], t_end=1.5, sample_dt=0.05)
    law = lambda x: np.clip(50 * np.cos(x), -3, 3)
    ref = solve_ivp(lambda t, y: [y[1], (law(y[0]) + 9.81 * 0.5 * np.sin(y[0])) / 0.25], (0, 1.5), [0, 0],
                    t_eval=tr.t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tr.column("theta"), ref.y[0], atol=1e-7)
    np.testing.assert_allclose(tr.inputs()["motor"], law(tr.column("theta")), atol=1e-12)
    assert np.max(np.abs(tr.inputs()["motor"])) == pytest.approx(3.0)
