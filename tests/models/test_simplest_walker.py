"""The simplest walker against Garcia, Chatterjee, Ruina & Coleman (1998) and its own asymptotics.

Reference values (see docs/references.md, section 2, for provenance):

* Garcia's simulation code for the paper (``run_doubpend.m``, 1998), fixed points "to 1e-10"
  at γ = 0.009: long period θ* = 0.20031090049483, θ̇* = −0.19983247291764, eigenvalues
  −0.19120868949940 ± 0.55633363687106i; short period θ* = 0.19393736960624,
  θ̇* = −0.20386692731962, eigenvalues 4.000 and 0.459.
* Bhounsule's ``simplestwalker.m`` (2013): the full long-period state
  [0.200310900563820, −0.199832473025474, 0.400621801127640, −0.015822999949030], t = 3.882.
* Garcia's equations and heel-strike map written out by hand and integrated by SciPy
  (tests/oracles/simplest_walker.py: DOP853 at rtol = atol = 1e-13, the map's Jacobian from the
  variational equations and the saltation matrix), computed here: long period θ* = 0.2003109005,
  eigenvalues −0.19009984 ± 0.55759878i, step period 3.882464; short period eigenvalues 4.00386
  and 0.45959. Garcia's printed eigenvalues differ from it by about 1e-3, more than the difference
  between the published fixed points, so they are checked to that looser tolerance only.
* Garcia et al. 1998, App. A.2 / Fig. 3 caption: small-slope expansion of the long-period
  gait, θ* ≈ Θ₀ γ^(1/3), θ̇* ≈ α Θ₀ γ^(1/3), period → τ₀, with τ₀ = 3.812092, Θ₀ = 0.970956,
  α = −1.045203. τ₀ is the root of the linearised closing condition
  ``3 cos τ + coth(τ/2) sin τ = −3`` and Θ₀ = tanh(τ₀/2)^(2/3), α = −coth(τ₀/2) follow from
  the energy balance; both are checked here as well.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import amble
from amble import Model, R, walker
from amble.analysis.poincare import find_fixed_point
from amble.models import load

GAMMA = 0.009
GARCIA_LONG = (0.20031090049483, -0.19983247291764)
GARCIA_LONG_EIG = complex(-0.19120868949940, 0.55633363687106)
GARCIA_SHORT = (0.19393736960624, -0.20386692731962)
GARCIA_SHORT_EIG = (4.000, 0.459)
BHOUNSULE_LONG = (0.200310900563820, 0.400621801127640, -0.199832473025474, -0.015822999949030)
TAU0, THETA0, ALPHA = 3.812092, 0.970956, -1.045203


@pytest.fixture(scope="module")
def system():
    return load("simplest-walker")


@pytest.fixture(scope="module")
def oracle_long() -> dict:
    from oracles.simplest_walker import LONG_GUESS, limit_cycle

    return limit_cycle(GAMMA, LONG_GUESS)


@pytest.fixture(scope="module")
def oracle_short() -> dict:
    from oracles.simplest_walker import SHORT_GUESS, limit_cycle

    return limit_cycle(GAMMA, SHORT_GUESS)


@pytest.fixture(scope="module")
def cycle(system):
    return find_fixed_point(system)


def _section_state(theta: float, theta_dot: float) -> list[float]:
    return [theta, 2 * theta, theta_dot, (1 - math.cos(2 * theta)) * theta_dot]


def test_long_period_fixed_point_matches_garcia(cycle, oracle_long):
    th, ph, thd, phd = cycle.fixed_point
    assert oracle_long["residual"] < 1e-13
    np.testing.assert_allclose(cycle.fixed_point, oracle_long["fixed_point"], rtol=0, atol=1e-10)
    assert cycle.state_names == ["theta", "phi", "theta_dot", "phi_dot"]
    assert th == pytest.approx(GARCIA_LONG[0], abs=1e-9)
    assert thd == pytest.approx(GARCIA_LONG[1], abs=1e-9)
    np.testing.assert_allclose(cycle.fixed_point, BHOUNSULE_LONG, rtol=0, atol=1e-9)
    # on the section: both feet on the slope, swing speed tied to the stance speed
    assert ph == pytest.approx(2 * th, abs=1e-12)
    assert phd == pytest.approx((1 - math.cos(2 * th)) * thd, abs=1e-12)


def test_long_period_step_time(cycle, oracle_long):
    assert cycle.step_time == pytest.approx(3.882, abs=5e-4)  # Bhounsule, 3 decimals
    assert cycle.step_time == pytest.approx(oracle_long["step_time"], abs=1e-9)


def test_long_period_multipliers(cycle, oracle_long):
    assert cycle.stable
    assert len(cycle.multipliers) == 2  # the heel strike forgets phi and phi_dot
    lam = cycle.multipliers[np.argmax(cycle.multipliers.imag)]
    ref = oracle_long["multipliers"][np.argmax(oracle_long["multipliers"].imag)]
    assert abs(lam - ref) < 1e-8  # both Jacobians are exact up to the integration tolerance
    assert abs(lam - GARCIA_LONG_EIG) < 2e-3


def test_short_period_gait_is_unstable(system, oracle_short):
    lc = find_fixed_point(system, _section_state(*GARCIA_SHORT))
    assert lc.fixed_point[0] == pytest.approx(GARCIA_SHORT[0], abs=1e-9)
    assert lc.fixed_point[2] == pytest.approx(GARCIA_SHORT[1], abs=1e-9)
    np.testing.assert_allclose(lc.fixed_point, oracle_short["fixed_point"], rtol=0, atol=1e-10)
    assert lc.step_time == pytest.approx(oracle_short["step_time"], abs=1e-9)
    assert not lc.stable
    np.testing.assert_allclose(sorted(abs(lc.multipliers), reverse=True), GARCIA_SHORT_EIG, atol=5e-3)
    np.testing.assert_allclose(sorted(lc.multipliers.real, reverse=True),
                               sorted(oracle_short["multipliers"].real, reverse=True), rtol=0, atol=1e-7)


def test_walks_fifty_steps_from_default_start(system):
    tr = amble.simulate(system, steps=60)
    assert tr.status == "completed" and tr.steps == 60
    # the walk stays on the stable gait: every heel strike lands at the published stance angle
    post = np.array([e.x_post for e in tr.step_events])
    np.testing.assert_allclose(post[:, 0], GARCIA_LONG[0], atol=1e-6)


def test_hip_energy_is_conserved_between_heel_strikes(system, cycle):
    """θ̈ = sin(θ − γ) is the hip pendulum: θ̇²/2 + cos(θ − γ) is constant during a step."""
    tr = amble.simulate(system, cycle.fixed_point, steps=1, sample_dt=0.01)
    keep = tr.t < tr.step_events[0].t
    th, thd = tr.column("theta")[keep], tr.column("theta_dot")[keep]
    e = thd**2 / 2 + np.cos(th - GAMMA)
    assert np.ptp(e) < 1e-9


def test_heel_strike_map_is_garcias(system):
    """One step from the section: the reset is θ⁺ = −θ⁻, φ⁺ = −2θ⁻, θ̇⁺ = cos 2θ⁻ θ̇⁻,
    φ̇⁺ = cos 2θ⁻ (1 − cos 2θ⁻) θ̇⁻, at the point where φ − 2θ rises through 0 with θ < 0."""
    tr = amble.simulate(system, _section_state(0.19, -0.2), steps=1)
    ev = tr.step_events[0]
    th, ph, thd, _ = ev.x_pre
    assert th < 0 and ph - 2 * th == pytest.approx(0, abs=1e-10)
    c = math.cos(2 * th)
    np.testing.assert_allclose(ev.x_post, [-th, -2 * th, c * thd, c * (1 - c) * thd], atol=1e-14)


def test_small_slope_asymptotics_close_on_themselves():
    """Garcia's printed τ₀, Θ₀, α satisfy the leading-order step conditions."""
    assert 3 * math.cos(TAU0) + math.sin(TAU0) / math.tanh(TAU0 / 2) + 3 == pytest.approx(0, abs=1e-5)
    assert math.tanh(TAU0 / 2) ** (2 / 3) == pytest.approx(THETA0, abs=1e-6)
    assert -1 / math.tanh(TAU0 / 2) == pytest.approx(ALPHA, abs=1e-6)


def test_stance_angle_scales_as_cube_root_of_slope(system):
    gammas = [1e-3, 1e-4, 1e-5]
    thetas, periods = [], []
    for g in gammas:
        th0 = THETA0 * g ** (1 / 3)
        lc = find_fixed_point(system, _section_state(th0, ALPHA * th0), params={"slope": g})
        th, thd = lc.fixed_point[0], lc.fixed_point[2]
        # leading order θ* = Θ₀ γ^(1/3), θ̇* = α Θ₀ γ^(1/3); the next terms are O(γ), with
        # coefficients of a few tenths (θ*) and about 1.3 (θ̇*, Garcia's αΘ₁ + c₁)
        assert abs(th - th0) < 0.3 * g
        assert abs(thd - ALPHA * th0) < 1.5 * g
        assert abs(lc.step_time - TAU0) < 2 * g ** (2 / 3)
        thetas.append(th)
        periods.append(lc.step_time)
    slope = np.polyfit(np.log(gammas), np.log(thetas), 1)[0]
    assert slope == pytest.approx(1 / 3, abs=2e-3)
    assert abs(periods[-1] - TAU0) < abs(periods[0] - TAU0)


def _finite_mass_walker():
    """The compass gait with hip mass 1 and foot masses β (g = l = 1), impact derived by amble,
    in amble's absolute leg angles: stance = γ − θ, swing = γ − θ + φ."""
    m = Model("simplest-walker-finite-beta")
    st, sw = m.coordinates("stance swing")
    beta, slope = m.parameters(beta=1e-3, slope=GAMMA)
    m.point("stance_foot", (0, 0), mass=beta)
    hip = m.point("hip", R(st), mass=1, link="stance_foot")
    m.point("swing_foot", hip - R(sw), mass=beta, link="hip")
    m.gravity(1)
    th, thd = GARCIA_LONG
    start = [GAMMA - th, GAMMA + th, -thd, -thd + (1 - math.cos(2 * th)) * thd]
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st}, start=start,
                  max_step_time=20.0)


def test_finite_foot_mass_converges_to_the_limit():
    """β = m/M → 0: the fixed point of the finite-mass walker approaches Garcia's at rate O(β)."""
    sys_ = _finite_mass_walker()
    errs = []
    for b in (1e-3, 1e-4, 1e-5):
        x = find_fixed_point(sys_, params={"beta": b}).fixed_point
        theta, theta_dot = GAMMA - x[0], -x[2]
        errs.append(max(abs(theta - GARCIA_LONG[0]), abs(theta_dot - GARCIA_LONG[1])))
    assert errs[-1] < 2e-6
    assert errs[0] / errs[1] == pytest.approx(10, rel=0.05)
    assert errs[1] / errs[2] == pytest.approx(10, rel=0.05)
