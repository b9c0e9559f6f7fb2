"""Exact sensitivities of compiled runs against central differences of the same compiled runs.

The variational equations and saltation matrices give ∂x(end)/∂(x0, p) and ∂t(end)/∂(x0, p) in
one run; differences of two perturbed runs approximate the same derivative with an error of
order h² (truncation) + tol/h (the integrator's error divided by the step): with h = 1e-6 and
tolerances 1e-12 about 1e-8 relative for one walking step; runs through many events use a larger
step over tighter tolerances. The agreement asked is 2e-7 of the derivative's scale. Every event kind is
covered: an impulsive impact with relabelling, a joint lock that drops a coordinate, a switching
surface where the right-hand side jumps, a guard and an explicit reset that depend on time, and a
terminal transition.
"""

import math

import numpy as np
import pytest
import sympy as sp

from amble import Explicit, Guard, HybridSystem, Model
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.engine import Options, run
from amble.simulation.simulate import initial_state, parameter_vector

OPTS = Options(rtol=1e-12, atol=1e-12, max_step_time=10.0)
H = 1e-6


def _check(system, x0, *, t_end=math.inf, steps=0, rel=2e-7, h=H, opts=OPTS):
    k = compiled(system, derivatives=True)
    p = parameter_vector(k, None, system)
    _, x0 = initial_state(system, k, np.asarray(x0, float), k.meta["modes"][0])
    r = run(k, p, 0, x0, t_end=t_end, steps=steps, opts=opts, sensitivities=True)
    assert r.status in ("completed", "end_time", "past_A"), r.status
    s = r.sensitivity

    def end(x, pv):
        q = run(k, pv, 0, x, t_end=t_end, steps=steps, opts=opts)
        assert q.code == r.code and q.mode == r.mode
        return q.x, q.t

    def central(f, x, e):
        # Richardson-extrapolated central difference: error O(h⁴) + noise/h
        d = [(np.r_[f(x + e * c)] - np.r_[f(x - e * c)]) / (2 * c) for c in (1.0, 0.5)]
        return (4 * d[1] - d[0]) / 3

    def state_end(x):
        xe, te = end(x, p)
        return np.r_[xe, te]

    def param_end(pv):
        xe, te = end(x0, pv)
        return np.r_[xe, te]

    n = r.x.size
    cols = [central(state_end, x0, h * np.eye(x0.size)[j]) / h for j in range(x0.size)]
    fd_x, fd_t = np.array(cols).T[:n], np.array(cols).T[n]
    steps_p = h * np.maximum(1.0, np.abs(p))
    cols = [central(param_end, p, steps_p[j] * np.eye(p.size)[j]) / steps_p[j] for j in range(p.size)]
    fd_p, fd_tp = np.array(cols).T[:n], np.array(cols).T[n]
    scale = max(1.0, np.max(np.abs(fd_x)), np.max(np.abs(fd_p)))
    np.testing.assert_allclose(s.dx_dx0, fd_x, atol=rel * scale, rtol=0)
    np.testing.assert_allclose(s.dx_dp, fd_p, atol=rel * scale, rtol=0)
    np.testing.assert_allclose(s.dt_dx0, fd_t, atol=rel * scale, rtol=0)
    np.testing.assert_allclose(s.dt_dp, fd_tp, atol=rel * scale, rtol=0)
    return r


@pytest.mark.parametrize("name", ["compass-gait", "kneed-biped", "rimless-wheel"])
def test_one_step_of_a_walker(name):
    """Impact and relabelling; for the kneed biped also the knee lock into a mode with one
    coordinate fewer."""
    system = load(name)
    r = _check(system, system.fixed_point_guess, steps=1)
    assert r.steps == 1 and np.any(r.sensitivity.dt_dx0 != 0)


def _jump_pendulum() -> HybridSystem:
    """A pendulum whose torque jumps where θ = 0.1 (from −a above to +b below): the flow crosses
    the switching surface transversally (θ̇ ≠ 0) with f⁺ ≠ f⁻."""
    m = Model("sens-jump")
    (th,) = m.coordinates(["theta"])
    g, a, b = m.parameters(g=9.81, a=3.0, b=1.0)
    m.point("bob", sp.Matrix([sp.sin(th), -sp.cos(th)]), mass=1.0)
    m.gravity(g)
    m.torque(sp.Piecewise((-a, th > 0.1), (b, True)), th)
    return HybridSystem("sens-jump", m)


#: Runs through many events: differences need a larger step over a tighter integration (their
#: noise, the integrator's error over h, grows with every located event).
TIGHT = Options(rtol=1e-13, atol=1e-13, max_step_time=10.0)


def test_switching_surface_saltation():
    r = _check(_jump_pendulum(), [0.6, 0.0], t_end=4.0, h=1e-4, opts=TIGHT)
    # the derivative differs from the smooth-flow one: the saltation at each crossing matters
    assert r.status == "end_time"


def _table_ball() -> HybridSystem:
    """A ball bouncing on a table that oscillates as A sin(ω t): a guard and a reset that
    depend on time (restitution e relative to the table)."""
    m = Model("sens-table")
    (z,) = m.coordinates(["z"])
    e, amp, w, g = m.parameters(e=0.8, A=0.05, w=5.0, g=9.81)
    m.point("ball", sp.Matrix([0, z]), mass=1.0)
    m.gravity(g)
    s = HybridSystem("sens-table", m)
    t = sp.Symbol("t", real=True)
    table_v = amp * w * sp.cos(w * t)
    s.transition("bounce", "sens-table", Guard(z - amp * sp.sin(w * t), -1),
                 Explicit(q=[z], qd=[-e * m.dot(z) + (1 + e) * table_v]))
    return s


def test_time_dependent_guard_and_reset():
    r = _check(_table_ball(), [0.5, 0.0], t_end=2.5, h=1e-4, opts=TIGHT)
    assert r.events >= 3


def _guarded_pendulum() -> HybridSystem:
    """A pendulum whose terminal guard ``A − θ`` fires when θ exceeds the parameter A."""
    m = Model("sens-terminal")
    (th,) = m.coordinates(["theta"])
    g, a = m.parameters(g=9.81, A=0.5)
    m.point("bob", sp.Matrix([sp.sin(th), -sp.cos(th)]), mass=1.0)
    m.gravity(g)
    s = HybridSystem("sens-terminal", m)
    s.terminal("past_A", "sens-terminal", Guard(a - th, -1), status="past_A")
    return s


def test_terminal_event_time():
    r = _check(_guarded_pendulum(), [0.0, 2.0])
    assert r.status == "past_A"
    # the end state lies on the guard θ = A for every perturbation: its θ row is the A column
    assert r.sensitivity.dx_dx0[0] == pytest.approx([0.0, 0.0], abs=1e-12)
