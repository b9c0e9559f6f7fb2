"""Controlled symmetry: the level-ground compass gait reproduces the passive slope gait turned
by the slope — fixed point and step time to 1e-10, the return maps conjugate by the turn to
1e-10 (so their multipliers are the same), and the multipliers of find_fixed_point (central
differences of step 1e-5, good to ~1e-9) to 1e-8."""

import numpy as np
import pytest

from amble.analysis.poincare import ReturnMap, find_fixed_point
from amble.models import load


@pytest.mark.parametrize("gamma", [0.05, 0.03])
def test_level_gait_is_the_passive_slope_gait_turned(gamma):
    passive = find_fixed_point(load("compass-gait"), params={"slope": gamma}, rtol=1e-13, atol=1e-13, tol=1e-12)
    level = find_fixed_point(load("compass-gait-level"), params={"emulated_slope": gamma}, rtol=1e-13,
                             atol=1e-13, tol=1e-12)
    turned = passive.fixed_point - np.array([gamma, gamma, 0.0, 0.0])
    np.testing.assert_allclose(level.fixed_point, turned, rtol=0, atol=1e-10)
    assert level.step_time == pytest.approx(passive.step_time, abs=1e-10)
    np.testing.assert_allclose(np.sort_complex(level.multipliers), np.sort_complex(passive.multipliers),
                               rtol=0, atol=1e-8)
    assert level.stable
    # P_level(x − c) = P_passive(x) − c around the fixed point: the Jacobians, hence every
    # multiplier, agree to the integration tolerance
    shift = np.array([gamma, gamma, 0.0, 0.0])
    Pp = ReturnMap(load("compass-gait"), {"slope": gamma}, rtol=1e-13, atol=1e-13)
    Pl = ReturnMap(load("compass-gait-level"), {"emulated_slope": gamma}, rtol=1e-13, atol=1e-13)
    rng = np.random.default_rng(1)
    for dx in 1e-2 * rng.standard_normal((4, 4)):
        x = passive.fixed_point + dx
        xp, tp = Pp(x)
        xl, tl = Pl(x - shift)
        np.testing.assert_allclose(xl, xp - shift, rtol=0, atol=1e-10)
        assert tl == pytest.approx(tp, abs=1e-10)


def test_the_controller_works_against_gravity_only():
    """With no emulated slope the law is zero (the passive walker on level ground)."""
    from amble import simulate

    tr = simulate(load("compass-gait-level"), params={"emulated_slope": 0.0}, t_end=0.5, sample_dt=0.05)
    assert np.allclose(tr.inputs()["hip"], 0, atol=1e-12) and np.allclose(tr.inputs()["ankle"], 0, atol=1e-12)
