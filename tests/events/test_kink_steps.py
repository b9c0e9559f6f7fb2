"""A kink of the right-hand side (a torque −k·max(θ, 0) that switches off at θ = 0, as a leg's
step-length torque does) costs the integrator a rejected step or two, not a cluster: a trial step
that ends beyond the switching surface is retried aimed just past it, the crossing is located in
the accepted step, and the step size after it resumes from the size before the kink."""

import math

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from systems import pendulum

import amble
from amble import HybridSystem, Options

K = 40.0  # N·m/rad: the kink's jump in ∂θ̈/∂θ


def _kinked(name: str) -> HybridSystem:
    m, _ = pendulum(name, lambda th, _thd, _m: -K * sp.Max(th, 0))
    return HybridSystem(name, m)


def _reference(x0, t_end):
    """Each smooth branch integrated on its own by SciPy, switching where θ crosses 0."""
    t, x, crossings = 0.0, np.array(x0, float), []
    side = 1.0 if x[0] > 0 else -1.0  # the branch: flipped at each crossing, not read off x there
    while t < t_end:
        f = lambda _t, y, s=side: [y[1], -9.81 * math.sin(y[0]) - (K * y[0] if s > 0 else 0.0)]  # noqa: E731
        ev = lambda _t, y: y[0]  # noqa: E731
        ev.terminal, ev.direction = True, -side
        r = solve_ivp(f, (t, t_end), x, method="DOP853", rtol=1e-13, atol=1e-13, events=ev)
        t, x = r.t[-1], r.y[:, -1]
        if r.status == 1:
            crossings.append(t)
            side = -side
    return x, crossings


def test_steps_across_a_kink_stay_long_and_accurate():
    x0, t_end = [0.4, 0.0], 4.0
    tr = amble.simulate(_kinked("ev-kink-max"), x0, t_end=t_end, sample_dt=0.0,
                        options=Options(rtol=1e-10, atol=1e-10))
    assert tr.status == "end_time", tr.message
    ref, crossings = _reference(x0, t_end)
    assert len(crossings) >= 4
    # SciPy switching the branches exactly at 1e-10 is within 3.4e-10; a crossing located on a step
    # with stages beyond the kink was 1.2e-8 off
    assert np.allclose(tr.final_state, ref, rtol=0, atol=1e-9), (tr.final_state, ref)
    dt = np.diff(tr.t)
    for tc in crossings:
        i = int(np.argmin(np.abs(tr.t - tc)))  # the row on the crossing
        assert abs(tr.t[i] - tc) < 1e-9
        # the step after the crossing is not collapsed: at least a third of the last one taken
        # before the step that reached the surface (the plain control restarts ~100× smaller)
        before, after = dt[i - 2], dt[i]
        assert after > before / 3, (tc, before, dt[i - 1], after)
