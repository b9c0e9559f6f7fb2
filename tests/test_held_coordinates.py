"""Held coordinates (``Model.hold``): a value a mode carries unchanged, such as where a foot
landed. A pendulum hung from a pivot whose place is a held coordinate swings as a pendulum on a
fixed pivot (SciPy's integration of θ̈ = −(g/l) sin θ), where the same coordinate left free
would slide under the swinging bob."""

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from amble import HybridSystem, Model, ModelError, derive, simulate

L, G, MASS = 0.8, 9.81, 2.0


def _pendulum(hold: bool) -> Model:
    m = Model("pivot-pendulum")
    (th,) = m.coordinates("theta")
    (p,) = m.coordinates("p", unit="m")
    m.point("pivot", (p, 0), mass=1.0)  # a slider: left free, it moves under the swinging bob
    m.point("bob", (p + L * sp.sin(th), -L * sp.cos(th)), mass=MASS, link="pivot")
    m.gravity(G)
    if hold:
        m.hold("p")
    return m


def test_held_pivot_swings_as_a_fixed_pendulum():
    eq = derive(_pendulum(hold=True))
    assert eq.M[1, :] == sp.Matrix([[0, 1]]) and eq.M[0, 1] == 0 and eq.h[1] == 0
    x0 = [0.5, 0.3, 0.0, 0.0]
    run = simulate(HybridSystem("held", _pendulum(hold=True)), x0, t_end=2.0, rtol=1e-12, atol=1e-12)
    ref = solve_ivp(lambda _t, s: [s[1], -G / L * math.sin(s[0])], (0.0, 2.0), [0.5, 0.0], method="DOP853",
                    rtol=1e-12, atol=1e-12)
    theta, p, theta_dot, p_dot = run.final_state
    assert abs(theta - ref.y[0, -1]) <= 1e-9 and abs(theta_dot - ref.y[1, -1]) <= 1e-9
    assert p == 0.3 and p_dot == 0.0
    # the same coordinate left free: the pivot slides (the momentum along x is conserved, not p)
    free = simulate(HybridSystem("free", _pendulum(hold=False)), x0, t_end=2.0, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(free.x[:, 1] - 0.3)) > 0.01


def test_holding_what_is_no_coordinate_is_refused():
    m = _pendulum(hold=False)
    with pytest.raises(ModelError, match="not a coordinate"):
        m.hold("q")
