"""A ball on compliant ground (Hunt–Crossley) against closed forms and an independent integration.

* Elastic (``d = 0``, no gravity): Hertz's law conserves energy, so the ball leaves with the
  speed ``v₀`` it came with, after the contact time of Hertz's impact
  ``t_c = 2 (δₘ/v₀) ∫₀¹ (1 − ξ^{5/2})^{−1/2} dξ = (4/5) B(2/5, 1/2) δₘ/v₀`` with the deepest
  penetration ``δₘ = (5 m v₀² / 4k)^{2/5}`` (energy balance ``½ m v₀² = (2/5) k δₘ^{5/2}``).
* Dissipative: the rebound speed equals SciPy's integration of the one-dimensional law
  ``m δ̈ = −k δ^{3/2} (1 + d δ̇)`` (written out here, nothing from amble), and energy never grows.
* At rest under gravity the ball sinks to where the spring carries its weight,
  ``δ* = (m g / k)^{2/3}``.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.special import beta

from amble import Guard, HybridSystem, Model, ModelError, compliant_contact, simulate

M, K, H = 2.0, 1.0e4, 0.05  # kg, N/m^1.5, start height (m)


def _ball(name: str, dissipation: float, g: float) -> HybridSystem:
    m = Model(name)
    x, z = m.coordinates(["x", "z"])
    k, d, grav = m.parameters(k=K, d=dissipation, g=g)
    m.point("ball", sp.Matrix([x, z]), mass=M)
    m.gravity(grav)
    compliant_contact(m, "ball", k, d)
    s = HybridSystem(name, m)
    s.terminal("back_up", name, Guard(z - H, 1), status="back_up")  # rising through the start height
    return s


def _hertz_contact_time(v0: float) -> float:
    depth = (5 * M * v0**2 / (4 * K)) ** 0.4
    return 0.8 * beta(0.4, 0.5) * depth / v0


@pytest.mark.parametrize("v0", [0.5, 2.0])
def test_an_elastic_bounce_returns_the_speed_after_hertz_contact_time(v0):
    tr = simulate(_ball("hc-elastic", 0.0, 0.0), [0.0, H, 0.3, -v0], t_end=10.0, sample_dt=1e-4)
    assert tr.status == "back_up"
    xd, zd = tr.x[-1, 2], tr.x[-1, 3]
    assert zd == pytest.approx(v0, rel=1e-8)
    assert xd == pytest.approx(0.3, rel=1e-12)  # no friction: the tangential speed is untouched
    assert tr.t[-1] == pytest.approx(2 * H / v0 + _hertz_contact_time(v0), rel=1e-8)
    # the ball went into the ground as deep as the energy balance says, and no deeper
    assert -tr.column("z").min() == pytest.approx((5 * M * v0**2 / (4 * K)) ** 0.4, rel=1e-3)


def _scipy_rebound(v0: float, d: float) -> float:
    """Rebound speed of m δ̈ = −k δ^1.5 (1 + d δ̇) from δ = 0, δ̇ = v0, ended where the force is zero."""
    def rhs(_, y):
        return [y[1], -K * max(y[0], 0.0) ** 1.5 * (1 + d * y[1]) / M]

    def released(_, y):  # δ back to zero, or the damping term cutting the force to zero
        return min(y[0], 1 + d * y[1]) if _ > 0 else 1.0
    released.terminal, released.direction = True, -1
    sol = solve_ivp(rhs, (0, 1), [0.0, v0], events=released, rtol=1e-12, atol=1e-14)
    delta, rate = sol.y_events[0][0]
    # after a cut (δ > 0, the force zero) the ball flies free through the rest of the depth
    return -rate


@pytest.mark.parametrize("d", [0.1, 0.5])
def test_a_dissipative_bounce_matches_an_independent_integration_and_loses_energy(d):
    v0 = 1.0
    tr = simulate(_ball("hc-damped", d, 0.0), [0.0, H, 0.0, -v0], t_end=10.0, sample_dt=1e-4)
    assert tr.status == "back_up"
    assert tr.x[-1, 3] == pytest.approx(_scipy_rebound(v0, d), rel=1e-7)
    assert tr.x[-1, 3] < v0
    # kinetic + Hertz potential (2/5) k δ^2.5 never grows
    z, zd = tr.column("z"), tr.column("z_dot")
    energy = 0.5 * M * zd**2 + 0.4 * K * np.maximum(-z, 0.0) ** 2.5
    assert np.max(np.diff(energy)) < 1e-9 * energy[0]


def test_at_rest_the_ball_sinks_until_the_ground_carries_its_weight():
    g = 9.81
    tr = simulate(_ball("hc-rest", 2.0, g), [0.0, 0.002, 0.0, 0.0], t_end=3.0, sample_dt=1e-3)
    assert tr.status == "end_time"
    assert -tr.x[-1, 1] == pytest.approx((M * g / K) ** (2 / 3), rel=1e-6)
    assert abs(tr.x[-1, 3]) < 1e-6


@pytest.mark.parametrize("kw, what", [({"stiffness": 0}, "stiffness must be positive"),
                                      ({"stiffness": 1, "dissipation": -1}, "dissipation must be ≥ 0"),
                                      ({"stiffness": 1, "exponent": 0.5}, "exponent must be ≥ 1")])
def test_bad_laws_are_refused(kw, what):
    m = Model("hc-bad")
    (z,) = m.coordinates(["z"])
    m.point("ball", sp.Matrix([0, z]), mass=1.0)
    with pytest.raises(ModelError, match=what):
        compliant_contact(m, "ball", **kw)
    with pytest.raises(ModelError, match="unknown point"):
        compliant_contact(m, "foot", 1.0)
