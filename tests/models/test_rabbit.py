"""RABBIT under HZD: as ε → 0 the full-order multipliers converge to the restricted Poincaré map
of the zero dynamics — computed here from the robot's full-order equations written out
independently (tests/oracles/rabbit_zero_dynamics.py: Kane's equations, the manifold q(θ) of the
Bézier constraints, the torso row for θ̈, the plastic impact for θ̇⁺ = δ θ̇⁻, SciPy's DOP853) —
and the gait is a stable, feasible period-1 walk between 0.5 and 1 m/s."""

import numpy as np
import pytest
import sympy as sp

from amble import derive
from amble.analysis.gait_check import check_gait
from amble.analysis.hzd import hybrid_invariance_error, impact_on_zero_dynamics
from amble.analysis.poincare import find_fixed_point
from amble.derivation.hzd import zero_dynamics
from amble.models import load


@pytest.fixture(scope="module")
def rabbit():
    return load("rabbit")


def _oracle(system):
    """The oracle's zero dynamics at the system's parameters and Bézier coefficients."""
    from oracles.rabbit_zero_dynamics import PARAMS, ZeroDynamics

    p = system.parameters
    alpha = [[p[f"alpha_{i}_{k}"] for k in range(6)] for i in range(4)]
    return ZeroDynamics(alpha, p["phase_start"], p["phase_end"], {name: p[name] for name in PARAMS})


def _restricted_scipy(system):
    lc = _oracle(system).limit_cycle(guess=1.0)
    assert lc["residual"] < 1e-12
    return lc["theta_dot"], lc["multiplier"], lc["step_time"]


@pytest.fixture(scope="module")
def restricted(rabbit):
    return _restricted_scipy(rabbit)


def test_amble_zero_dynamics_agree_with_the_oracle(rabbit):
    """amble's symbolic zero dynamics (derivation/hzd.py) and impact on Z (analysis/hzd.py) against
    the oracle's numerical ones, at states across the step."""
    m = rabbit.modes["rabbit"]
    p = rabbit.parameters
    eq = derive(m)
    zd = zero_dynamics(m, eq.M, eq.h, eq.Gamma, eq.B)
    f = sp.lambdify([zd.theta, zd.theta_dot], zd.theta_ddot.xreplace({s: p[str(s)] for s in m.params}), cse=True)
    oracle = _oracle(rabbit)
    for theta in np.linspace(p["phase_start"], p["phase_end"], 7):
        for theta_dot in (0.5, 0.9, 1.4):
            assert float(f(theta, theta_dot)) == pytest.approx(oracle.theta_ddot(theta, theta_dot), abs=1e-10)
    assert impact_on_zero_dynamics(rabbit).delta == pytest.approx(oracle.impact_ratio(), abs=1e-12)


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
    # and the full state is the oracle's point of Z: q = q(θ⁺), q̇ = q_θ θ̇⁺
    q, q_theta, _ = _oracle(rabbit).q_of(rabbit.parameters["phase_start"])
    np.testing.assert_allclose(x[:5], q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(x[5:], q_theta * w, rtol=0, atol=1e-7)


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
