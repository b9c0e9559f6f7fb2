"""RABBIT under HZD: as ε → 0 the full-order multipliers converge to the restricted Poincaré map
of the zero dynamics — computed here independently by integrating the 1-DOF zero dynamics in
time with SciPy — and the gait is a stable, feasible period-1 walk between 0.5 and 1 m/s."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from amble import derive
from amble.analysis.gait_check import check_gait
from amble.analysis.hzd import hybrid_invariance_error, impact_on_zero_dynamics
from amble.analysis.poincare import find_fixed_point
from amble.derivation.hzd import zero_dynamics
from amble.models import load


@pytest.fixture(scope="module")
def rabbit():
    return load("rabbit")


def _restricted_scipy(system):
    m = system.modes["rabbit"]
    p = system.parameters
    eq = derive(m)
    zd = zero_dynamics(m, eq.M, eq.h, eq.Gamma, eq.B)
    f = sp.lambdify([zd.theta, zd.theta_dot], zd.theta_ddot.xreplace({s: p[str(s)] for s in m.params}), cse=True)
    th0, th1 = p["phase_start"], p["phase_end"]
    delta = impact_on_zero_dynamics(system).delta

    def P(w):
        end = lambda t, y: y[0] - th1
        end.terminal, end.direction = True, 1
        sol = solve_ivp(lambda t, y: [y[1], f(y[0], y[1])], (0, 5), [th0, w], events=end, rtol=1e-12, atol=1e-12)
        return delta * sol.y_events[0][0][1], sol.t_events[0][0]

    w = 1.0
    for _ in range(80):
        w = P(w)[0]
    h = 1e-5
    return w, (P(w + h)[0] - P(w - h)[0]) / (2 * h), P(w)[1]


@pytest.fixture(scope="module")
def restricted(rabbit):
    return _restricted_scipy(rabbit)


def test_the_gait_multiplier_is_the_restricted_one(rabbit, restricted):
    """At the default ε = 0.1: the orbit lies on Z, so one multiplier is the restricted map's."""
    assert hybrid_invariance_error(rabbit) < 1e-9
    w, lam, T = restricted
    assert 0 < lam < 1
    lc = find_fixed_point(rabbit)
    mods = np.sort(np.abs(lc.multipliers))[::-1]
    assert mods[0] == pytest.approx(lam, abs=1e-6) and mods[1] < 0.1
    assert lc.step_time == pytest.approx(T, abs=1e-6)
    x = lc.fixed_point  # θ̇⁺ = torso_dot + stance_hip_dot + stance_knee_dot/2 is the restricted fixed point
    assert x[5] + x[6] + x[8] / 2 == pytest.approx(w, abs=1e-7)


def test_multipliers_converge_to_the_restricted_map(rabbit, restricted):
    w, lam, T = restricted
    second = []
    for eps in (0.2, 0.1, 0.05, 0.025):
        lc = find_fixed_point(rabbit, params={"epsilon": eps})
        mods = np.abs(lc.multipliers)
        near = int(np.argmin(np.abs(mods - lam)))
        assert mods[near] == pytest.approx(lam, abs=1e-6)  # the orbit lies on Z (invariant): exact for every ε
        assert lc.step_time == pytest.approx(T, abs=1e-6)
        second.append(np.max(np.delete(mods, near)))
    assert second[0] > 0.9  # a slow controller: the transverse dynamics dominate, barely stable
    assert second[0] > second[1] > second[2] > second[3]  # the transverse multipliers vanish as ε → 0
    assert second[3] < 1e-3


def test_the_gait_is_a_feasible_walk(rabbit):
    lc = find_fixed_point(rabbit)
    assert lc.stable
    tr = lc.trajectory()
    hip = tr.world_points()["hip"][:, 0]
    speed = (hip[-1] - hip[0]) / (tr.t[-1] - tr.t[0])
    assert 0.5 < speed < 1.0
    c = check_gait(tr)
    assert c.normal_force_positive and c.friction_ok and c.swing_foot_clear
    assert c.impulse_positive and c.trailing_foot_leaves and c.within_limits
