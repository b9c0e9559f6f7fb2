"""The rimless wheel against its closed forms (Tedrake, *Underactuated Robotics*, "The Rimless
Wheel"; McGeer 1990; Coleman et al. 1997; see docs/references.md, section 4).

Post-impact speed of the rolling cycle ``ω* = cot(2α) sqrt(4 (g/l) sin α sin γ)``; return map
``ω[n+1] = cos(2α) sqrt(ω[n]² + 4 (g/l) sin α sin γ)`` above the rolling threshold
``ω₁ = sqrt(2 (g/l)(1 − cos(γ − α)))`` and ``ω[n+1] = −cos(2α) ω[n]`` below it (rocking back);
multiplier ``cos²(2α)``. The impact itself is derived by amble from the model (a plastic
collision of the next spoke's foot), so these tests also check the derived impact.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import amble
from amble.analysis.poincare import find_fixed_point
from amble.models import load

DEFAULTS = {"m": 1.0, "l": 1.0, "g": 9.81, "alpha": math.pi / 8, "slope": 0.08}
OTHER = {"m": 3.0, "l": 0.5, "g": 9.81, "alpha": math.pi / 6, "slope": 0.2}


def omega_star(p: dict[str, float]) -> float:
    a, gam = p["alpha"], p["slope"]
    return math.sqrt(4 * p["g"] / p["l"] * math.sin(a) * math.sin(gam)) / math.tan(2 * a)


def omega_1(p: dict[str, float]) -> float:
    return math.sqrt(2 * p["g"] / p["l"] * (1 - math.cos(p["slope"] - p["alpha"])))


@pytest.fixture(scope="module")
def system():
    return load("rimless-wheel")


def test_defaults_are_drakes(system):
    assert system.parameters == pytest.approx(DEFAULTS)
    assert omega_star(DEFAULTS) == pytest.approx(1.095462839648, abs=1e-12)  # docs/references.md §4


@pytest.mark.parametrize("params", [DEFAULTS, OTHER], ids=["drake-defaults", "six-spokes"])
def test_rolling_fixed_point_and_multiplier_match_closed_form(system, params):
    assert omega_star(params) > omega_1(params)  # the rolling cycle exists here
    lc = find_fixed_point(system, [params["slope"] - params["alpha"], 1.2 * omega_star(params)], params=params)
    theta, theta_dot = lc.fixed_point
    assert theta == pytest.approx(params["slope"] - params["alpha"], abs=1e-12)
    assert theta_dot == pytest.approx(omega_star(params), abs=1e-8)
    assert lc.section_coordinates == ["theta_dot"]
    assert len(lc.multipliers) == 1
    assert abs(lc.multipliers[0] - math.cos(2 * params["alpha"]) ** 2) < 1e-8
    assert lc.stable


@pytest.mark.parametrize("params", [DEFAULTS, OTHER], ids=["drake-defaults", "six-spokes"])
def test_exact_multiplier_to_twelve_digits(system, params):
    """The variational equations and the saltation matrix of the derived impact give the
    multiplier to the integration tolerance (central differences stop near 1e-9)."""
    lc = find_fixed_point(system, [params["slope"] - params["alpha"], omega_star(params)], params=params,
                          rtol=1e-14, atol=1e-14, tol=1e-13)
    assert abs(lc.multipliers[0] - math.cos(2 * params["alpha"]) ** 2) < 1e-12


def test_default_fixed_point_search(system):
    lc = find_fixed_point(system)
    assert lc.fixed_point[1] == pytest.approx(omega_star(DEFAULTS), abs=1e-8)
    assert lc.step_time == pytest.approx(1.0345498, abs=1e-6)  # docs/references.md §4 [R]
    assert lc.step_time == pytest.approx(step_time(DEFAULTS), abs=1e-9)


def step_time(p: dict[str, float]) -> float:
    """Time (s) from θ = γ − α to γ + α on the rolling cycle, by quadrature of the energy integral
    θ̇² = ω*² + 2 (g/l)(cos(γ − α) − cos θ) of θ̈ = (g/l) sin θ."""
    from scipy.integrate import quad

    a, gam, w = p["alpha"], p["slope"], omega_star(p)
    speed = lambda th: math.sqrt(w**2 + 2 * p["g"] / p["l"] * (math.cos(gam - a) - math.cos(th)))  # noqa: E731
    return quad(lambda th: 1 / speed(th), gam - a, gam + a, epsabs=1e-12, epsrel=1e-12)[0]


def test_derived_impact_keeps_angular_momentum_about_the_new_foot(system):
    """One step: θ⁻ = γ + α, then θ⁺ = γ − α and θ̇⁺ = cos(2α) θ̇⁻, the pre-impact speed
    following from energy conservation: θ̇⁻² = θ̇₀² + 4 (g/l) sin α sin γ."""
    p = DEFAULTS
    w0 = 1.3
    tr = amble.simulate(system, [p["slope"] - p["alpha"], w0], steps=1)
    ev = tr.step_events[0]
    w_pre = math.sqrt(w0**2 + 4 * p["g"] / p["l"] * math.sin(p["alpha"]) * math.sin(p["slope"]))
    np.testing.assert_allclose(ev.x_pre, [p["slope"] + p["alpha"], w_pre], atol=1e-9)
    np.testing.assert_allclose(ev.x_post, [p["slope"] - p["alpha"], math.cos(2 * p["alpha"]) * ev.x_pre[1]],
                               atol=1e-12)


def test_return_map_is_the_closed_form(system):
    p = DEFAULTS
    c = 4 * p["g"] / p["l"] * math.sin(p["alpha"]) * math.sin(p["slope"])
    tr = amble.simulate(system, steps=6)
    w = [1.5] + [e.x_post[1] for e in tr.step_events]
    for a, b in zip(w, w[1:]):
        assert b == pytest.approx(math.cos(2 * p["alpha"]) * math.sqrt(a**2 + c), abs=1e-9)


def test_rocking_back_below_the_rolling_threshold(system):
    """Below ω₁ the hub does not get over the top: it rolls back onto the previous spoke and
    ω[n+1] = −cos(2α) ω[n] (Tedrake's piecewise return map)."""
    p = DEFAULTS
    w0 = 0.5 * omega_1(p)
    tr = amble.simulate(system, [p["slope"] - p["alpha"], w0], t_end=5.0)
    first = tr.events[0]
    assert first.name == "back_strike"
    np.testing.assert_allclose(first.x_post, [p["slope"] + p["alpha"], -math.cos(2 * p["alpha"]) * w0], atol=1e-9)


def test_walks_fifty_steps_from_default_start(system):
    tr = amble.simulate(system, steps=60)
    assert tr.status == "completed" and tr.steps == 60
    # multiplier 1/2: after 60 steps the start's offset of 0.4 rad/s is gone (down to the
    # integration tolerance of simulate, 1e-10)
    assert tr.final_post_impact_state[1] == pytest.approx(omega_star(DEFAULTS), abs=1e-9)


def test_energy_conserved_between_impacts_and_lost_at_them(system):
    tr = amble.simulate(system, steps=3, sample_dt=0.005)
    k, v = tr.energy().T
    t_imp = [e.t for e in tr.step_events]
    for t0, t1 in zip([0.0, *t_imp[:-1]], t_imp):
        inside = (tr.t > t0 + 1e-9) & (tr.t < t1 - 1e-9)
        assert np.ptp((k + v)[inside]) < 1e-8
    # the impact keeps cos²(2α) of the kinetic energy: K⁺ = cos²(2α) K⁻
    p = DEFAULTS
    for e in tr.step_events:
        k_pre = 0.5 * p["m"] * p["l"] ** 2 * e.x_pre[1] ** 2
        k_post = 0.5 * p["m"] * p["l"] ** 2 * e.x_post[1] ** 2
        assert k_post == pytest.approx(math.cos(2 * p["alpha"]) ** 2 * k_pre, rel=1e-12)
