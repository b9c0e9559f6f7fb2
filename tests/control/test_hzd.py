"""Hybrid zero dynamics on the compass gait (one input at the hip): the derived controller
against HZD theory — zero outputs, hybrid invariance, and the full multipliers against the
restricted Poincaré map of the 1-DOF zero dynamics integrated with SciPy."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from amble import Model, ModelError, derive, simulate, walker
from amble.analysis.hzd import hybrid_invariance_error, impact_on_zero_dynamics, invariant_parameters, restricted_map
from amble.analysis.poincare import find_fixed_point
from amble.derivation.hzd import zero_dynamics
from amble.models.compass_gait import model as compass_model


def _compass_hzd():
    m = compass_model("cg-hzd")
    st, sw = m.q
    slope = m.symbol("slope")
    m.actuator("hip_torque", on=sw - st)
    m.virtual_constraints([sw], st, [[0.3168, 0.1, -0.1, -0.2168]], (-0.2168, 0.3168), epsilon=0.05)
    return m, walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st},
                     start=[-0.2168, 0.3168, 1.0839, 0.3981])


@pytest.fixture(scope="module")
def hzd():
    m, s = _compass_hzd()
    return m, s, invariant_parameters(s)


def test_the_controller_zeroes_the_outputs(hzd):
    """From a state off Z, y → 0 with the critically damped dynamics ÿ = −kd ẏ/ε − kp y/ε²
    (kp = 1, kd = 2): y(t) = (y₀ + (ẏ₀ + y₀/ε) t) e^{−t/ε} until the footfall."""
    m, s, p = hzd
    vc = m.virtual
    tr = simulate(s, [-0.2, 0.25, 1.2, 0.0], params=p, steps=1, sample_dt=0.01)
    pre = np.arange(len(tr.t)) < np.flatnonzero(tr.t == tr.events[0].t)[0] + 1  # up to the pre-impact row
    ys = sp.lambdify([*m.q, *m.params], vc.y[0])
    y = np.array([ys(a, b, *[p[str(q)] for q in m.params]) for a, b in zip(tr.column("stance"), tr.column("swing"))])
    eps = p["epsilon"]
    H = m.jacobian(vc.y)
    yd0 = float((H * sp.Matrix(m.qd)).subs({**dict(zip(m.q + m.qd, [-0.2, 0.25, 1.2, 0.0])),
                                             **{q: p[str(q)] for q in m.params}})[0])
    exact = (y[0] + (yd0 + y[0] / eps) * tr.t) * np.exp(-tr.t / eps)
    np.testing.assert_allclose(y[pre], exact[pre], atol=1e-8)


def test_hybrid_invariance_by_design(hzd):
    m, s, p = hzd
    assert hybrid_invariance_error(s) > 0.1  # the declared coefficients are not invariant
    imp = impact_on_zero_dynamics(s, p)
    assert imp.error < 1e-12
    assert abs(imp.guard) < 1e-12  # Φ(θ⁻) is on the footfall surface


def _restricted_multiplier_scipy(m, s, p):
    """The restricted map θ̇⁺ ↦ δ θ̇⁻(θ̇⁺) integrated in time with SciPy, its fixed point and
    multiplier by a central difference."""
    eq = derive(m)
    zd = zero_dynamics(m, eq.M, eq.h, eq.Gamma, eq.B)
    ps = {q: p[str(q)] for q in m.params}
    f = sp.lambdify([zd.theta, zd.theta_dot], zd.theta_ddot.xreplace(ps))
    th0, th1 = p["phase_start"], p["phase_end"]
    delta = impact_on_zero_dynamics(s, p).delta

    def P(w):
        end = lambda t, y: y[0] - th1
        end.terminal, end.direction = True, 1
        sol = solve_ivp(lambda t, y: [y[1], f(y[0], y[1])], (0, 10), [th0, w], events=end, rtol=1e-12, atol=1e-12)
        return delta * sol.y_events[0][0][1]

    w = 1.0
    for _ in range(60):  # fixed-point iteration of a contraction
        w = P(w)
    h = 1e-5
    return w, (P(w + h) - P(w - h)) / (2 * h)


def test_full_multipliers_converge_to_the_restricted_map(hzd):
    m, s, p = hzd
    w, lam = _restricted_multiplier_scipy(m, s, p)
    rm = restricted_map(s, p)
    assert rm.multiplier == pytest.approx(lam, abs=1e-7)
    transverse = []
    for eps in (0.1, 0.05, 0.02):
        lc = find_fixed_point(s, rm.x_post, params={**p, "epsilon": eps})
        mods = np.sort(np.abs(lc.multipliers))
        assert mods[-1] == pytest.approx(lam, abs=1e-7)
        assert lc.fixed_point[2] == pytest.approx(w, abs=1e-8)  # θ̇⁺ of the gait
        transverse.append(mods[-2])
    assert transverse[0] > transverse[1] > transverse[2] and transverse[2] < 1e-6


def test_hzd_errors():
    m = Model("bad")
    a, b = m.coordinates("a b")
    m.actuator("u", on=b)
    with pytest.raises(ModelError, match="one output per input"):
        m.virtual_constraints([a, b], a, [[0, 1], [0, 1]], (0, 1))
    with pytest.raises(ModelError, match="rows"):
        m.virtual_constraints([b], a, [[0, 1], [0]], (0, 1))
