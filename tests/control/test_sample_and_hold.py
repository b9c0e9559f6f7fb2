"""Sample-and-hold control against SciPy integrating the same held law interval by interval."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from amble import HybridSystem, Model, ModelError, R, simulate
from amble.modelling.sampled import sample_and_hold


def _pendulum():
    m = Model("held-pendulum")
    (th,) = m.coordinates("theta")
    m.point("pivot", (0, 0))
    m.point("bob", 0.5 * R(th), mass=1.0, link="pivot")
    m.gravity(9.81)
    u = m.actuator("motor", on=th, limit=6.0)
    m.control({u: -30 * th - 4 * m.dot(th)}, saturate=True)
    s = HybridSystem("held-pendulum", m)
    s.default_start["held-pendulum"] = [0.4, 0.0]
    return s


def test_held_law_matches_an_interval_by_interval_integration():
    rate = 50.0
    s = sample_and_hold(_pendulum(), rate)
    assert s.state_names() == ["theta", "clock", "held_motor", "theta_dot", "clock_dot", "held_motor_dot"]
    tr = simulate(s, t_end=1.0, sample_dt=0.0)
    law = lambda y: np.clip(-30 * y[0] - 4 * y[1], -6, 6)
    y, t = np.array([0.4, 0.0]), 0.0
    for _ in range(int(rate)):  # one sample, then the held torque for 1/rate s
        u = law(y)
        sol = solve_ivp(lambda _t, z: [z[1], (u + 9.81 * 0.5 * np.sin(z[0])) / 0.25], (t, t + 1 / rate), y,
                        rtol=1e-12, atol=1e-12)
        y, t = sol.y[:, -1], t + 1 / rate
    assert tr.final_state[0] == pytest.approx(y[0], abs=1e-8)
    assert tr.final_state[3] == pytest.approx(y[1], abs=1e-8)
    held = tr.inputs()["motor"]
    assert np.all(np.abs(held) <= 6.0)
    assert len(tr.events) == int(rate) - 1  # samples at 1/rate, 2/rate, … before t = 1 s (the first is the start)


def test_bad_rates_and_laws():
    with pytest.raises(ModelError, match="positive"):
        sample_and_hold(_pendulum(), 0)
    m = Model("dyn")
    (th,) = m.coordinates("theta")
    m.point("pivot", (0, 0))
    m.point("bob", R(th), mass=1.0, link="pivot")
    u = m.actuator("motor", on=th)
    _, h = m.dynamics()
    m.control({u: h[0]})
    with pytest.raises(ModelError, match="sample-and-hold"):
        sample_and_hold(HybridSystem("dyn", m), 100)
