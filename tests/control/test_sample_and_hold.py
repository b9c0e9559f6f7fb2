"""Sample-and-hold control against SciPy integrating the same held law interval by interval."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from amble import HybridSystem, Model, ModelError, R, simulate
from amble.modelling.sampled import sample_and_hold
from amble.models.compass_gait import model as compass_model


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
        sol = solve_ivp(lambda _t, z, u=u: [z[1], (u + 9.81 * 0.5 * np.sin(z[0])) / 0.25], (t, t + 1 / rate), y,
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
    _, h = m.mass_and_bias()
    m.control({u: h[0]})
    with pytest.raises(ModelError, match="sample-and-hold"):
        sample_and_hold(HybridSystem("dyn", m), 100)


def test_a_walker_sampled_at_1khz_walks_like_the_continuous_one():
    """Footfalls leave the clock and the held input alone; at 1 kHz the gait differs from the
    continuous law's by O(1/rate)."""
    from amble import walker

    m = compass_model("compass-pd")
    st, sw = m.q
    slope = m.symbol("slope")
    u = m.actuator("hip_torque", on=sw - st)
    m.control({u: -5 * (sw + st) - (m.dot(sw) + m.dot(st))})
    pd = walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st},
                start=[-0.2168, 0.3168, 1.0839, 0.3981])
    cont = simulate(pd, steps=3, samples=False)
    held = simulate(sample_and_hold(pd, 1000.0), steps=3, samples=False)
    assert held.status == "completed" and held.steps == 3
    x = held.final_state
    np.testing.assert_allclose(x[[0, 1, 4, 5]], cont.final_state, atol=1e-3)
    assert x[6] == 1.0 and x[7] == 0.0  # clock_dot, held_hip_torque_dot
    assert held.t[-1] == pytest.approx(cont.t[-1], abs=1e-3)
