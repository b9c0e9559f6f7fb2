"""A force that switches (Piecewise, sign, …) made the integrator creep
across the kink forever. Its switching surfaces are now events without a reset, and a flow that
points into a surface from both sides ends the run as ``sliding`` (time and surface reported)."""

import math

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from systems import coulomb_pendulum, pendulum, switching_pendulum

import amble
from amble import HybridSystem, Options
from amble.derivation.switching import switching_surfaces

_BUDGET = Options(max_steps_between_events=5000, max_integrator_steps=20000)


def test_surfaces_are_extracted_from_every_switching_function():
    x, v, k = sp.symbols("x v k", real=True)
    exprs = [sp.Piecewise((-1, x + v / 2 > 0), (1, True)) + sp.sign(v) + sp.Abs(x - 1) + sp.Heaviside(v - 2)
             + sp.Max(x, v) + sp.Min(x, k) + sp.sign(k)]
    found = switching_surfaces(exprs, [x, v])
    expected = [x + v / 2, v, x - 1, v - 2, x - v, x - k]
    assert all(any(sp.expand(f - e) == 0 or sp.expand(f + e) == 0 for f in found) for e in expected), found
    assert len(found) == 6  # sign(k): parameters only, constant during a run


def test_switching_controller_ends_sliding_instead_of_hanging():
    tr = amble.simulate(switching_pendulum(), [0.3, 0.0], t_end=0.05, sample_dt=0.0, options=_BUDGET)
    tr2 = amble.simulate(switching_pendulum(), [0.3, 0.0], t_end=2.0, sample_dt=0.0, options=_BUDGET)
    assert tr.status in ("end_time", "sliding"), tr.message
    assert tr2.status == "sliding", tr2.message
    th, thd = tr2.final_state
    assert abs(th + 0.5 * thd) < 1e-8  # on the surface θ + θ̇/2 = 0, to the integration tolerance
    assert "sliding on switching surface" in tr2.message and "\n" not in tr2.message
    assert tr2.t.size < 2000  # a bounded number of integrator steps
    # before reaching it, the flow is the smooth one of the +surface side: θ̈ = −g sin θ − 20
    # (integrated a little past amble's end: its located time may fall on either side of the true one)
    ref = solve_ivp(lambda _t, y: [y[1], -9.81 * math.sin(y[0]) - 20.0], (0, tr2.t[-1] + 1e-6), [0.3, 0.0],
                    rtol=1e-12, atol=1e-12, events=lambda _t, y: y[0] + 0.5 * y[1])
    t_hit = ref.t_events[0][0]
    assert abs(tr2.t[-1] - t_hit) < 1e-8


def test_coulomb_friction_sticks_where_the_closed_form_says():
    # −6 sign(θ̇): between turning points  ½θ̇² − g cos θ  drops by 6 |Δθ|; at a turning point θ₁
    # the pendulum sticks when g |sin θ₁| ≤ 6 (static friction holds it), else it swings back
    g, mu, th0 = 9.81, 6.0, 1.2
    th = th0
    for _ in range(10):
        if g * abs(math.sin(th)) <= mu:
            break
        sgn = -1.0 if th > 0 else 1.0  # direction of motion from this turning point
        f = lambda x, a=th, s=sgn: g * (math.cos(x) - math.cos(a)) - mu * abs(x - a)  # noqa: E731
        th = brentq(f, th + sgn * 1e-9, th + sgn * 2 * abs(th) + sgn * 1e-3 if th != 0 else sgn * 3.0)
    tr = amble.simulate(coulomb_pendulum(), [th0, 0.0], t_end=30.0, sample_dt=0.0, options=_BUDGET)
    assert tr.status == "sliding", tr.message
    assert abs(tr.final_state[1]) < 1e-8
    assert abs(tr.final_state[0] - th) < 1e-8
    assert tr.t.size < 5000


def test_a_transversal_kink_is_crossed_and_located():
    # τ = −k|θ| ... a kink at θ = 0 that the flow crosses: the run restarts there and stays accurate
    m, _ = pendulum("ev-abs", lambda th, thd, _: -2.0 * sp.Abs(th))
    s = HybridSystem("ev-abs", m)
    tr = amble.simulate(s, [0.5, 0.0], t_end=3.0, sample_dt=0.0, options=_BUDGET)
    assert tr.status == "end_time", tr.message
    ref = solve_ivp(lambda _t, y: [y[1], -9.81 * math.sin(y[0]) - 2.0 * abs(y[0])], (0, 3.0), [0.5, 0.0],
                    rtol=1e-13, atol=1e-13, method="DOP853", max_step=1e-3)
    assert np.allclose(tr.final_state, ref.y[:, -1], atol=1e-7)
    # a row sits on each crossing of θ = 0
    assert np.min(np.abs(tr.x[:, 0])) < 1e-12
