"""Compass-gait limit cycle against Goswami, Thuilot & Espiau (1996, INRIA RR-2996; 1998 IJRR).

Their state is (θ_ns, θ_s, θ̇_ns, θ̇_s) with angles of the opposite sign to ours (Drake's
convention: stance, swing, stance_dot, swing_dot); so stance = −θ_s, swing = −θ_ns. The widely
quoted fixed point at φ = 3°, g = 9.8 is (θ_ns, θ_s, θ̇_ns, θ̇_s) = (−0.3234, 0.2187, −0.3772,
−1.0918) (four digits); the first period doubling is reported at φ = 4.37° (1998).
See docs/references.md for the sources of every number. To all digits: their equations written
out and integrated by SciPy (tests/oracles/compass_gait.py).
"""

import functools
import math

import numpy as np
import pytest

from amble import ConvergenceError
from amble.analysis.poincare import ReturnMap, find_fixed_point


@functools.cache
def goswami_oracle(slope: float) -> tuple[np.ndarray, np.ndarray]:
    """The post-impact fixed point in our coordinates (g = 9.81) and the multipliers of
    Goswami's walker integrated by SciPy."""
    from oracles.compass_gait import fixed_point

    x, jac = fixed_point(slope)
    return np.array([-x[1], -x[0], -x[3], -x[2]]), np.linalg.eigvals(jac)


def test_fixed_point_matches_goswami_at_3_degrees(compass):
    lc = find_fixed_point(compass, params={"slope": math.radians(3.0), "g": 9.8})
    th_ns, th_s, thd_ns, thd_s = -0.3234, 0.2187, -0.3772, -1.0918
    expected = np.array([-th_s, -th_ns, -thd_s, -thd_ns])
    assert np.allclose(lc.fixed_point, expected, atol=6e-5)
    assert lc.residual < 1e-10
    assert lc.stable
    # on the section: the new swing foot is on the slope, swing + stance = 2φ
    assert abs(lc.fixed_point[0] + lc.fixed_point[1] - 2 * math.radians(3.0)) < 1e-12


def test_multipliers_are_those_of_the_step_map(compass):
    lc = find_fixed_point(compass, params={"slope": math.radians(3.0)})
    # Independent check of the finite-difference Jacobian: the multipliers must describe how a
    # small perturbation on the section decays under the map itself.
    P = ReturnMap(compass, {"slope": math.radians(3.0)})
    x = lc.fixed_point.copy()
    d = np.array([1e-4, -1e-4, 3e-4, -2e-4])  # stance/swing change together: stays on the section
    y = x + d
    norms = []
    for _ in range(12):
        y, _ = P(y)
        norms.append(np.linalg.norm(y - x))
    rate = (norms[-1] / norms[-5]) ** (1 / 4)
    assert abs(rate - max(abs(lc.multipliers))) < 0.02
    assert len(lc.multipliers) == 3  # 4 states minus the section constraint
    # and to all digits against Goswami's equations integrated by SciPy (central differences, ~1e-9)
    x_ref, mu_ref = goswami_oracle(math.radians(3.0))
    np.testing.assert_allclose(lc.fixed_point, x_ref, rtol=0, atol=1e-10)
    np.testing.assert_allclose(np.sort_complex(lc.multipliers), np.sort_complex(mu_ref), rtol=0, atol=1e-7)


def test_first_period_doubling_where_goswami_reports_it(compass):
    # The dominant multiplier crosses −1 (period doubling) at φ ≈ 4.37° (Goswami et al. 1998).
    def leading(deg, guess=None):
        lc = find_fixed_point(compass, guess, params={"slope": math.radians(deg)})
        return lc.multipliers[np.argmin(lc.multipliers.real)], lc.fixed_point

    _, g = leading(3.0)  # continuation: the basin shrinks as the doubling nears
    _, g = leading(4.0, g)
    below, g = leading(4.30, g)
    above, _ = leading(4.45, g)
    assert below.real > -1 and abs(below) < 1
    assert above.real < -1 and abs(above.imag) < 1e-9
    lo, hi = 4.30, 4.45
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        mu, g = leading(mid, g)
        lo, hi = (lo, mid) if mu.real < -1 else (mid, hi)
    assert abs(lo - 4.37) < 0.05


def test_period_two_orbit_beyond_the_doubling(compass):
    import amble

    slope = math.radians(4.6)
    g = None
    for deg in (3.0, 4.0, 4.3, 4.6):  # continuation along the slope
        lc1 = find_fixed_point(compass, g, params={"slope": math.radians(deg)})
        g = lc1.fixed_point
    assert not lc1.stable  # the period-1 gait lost stability...
    walk = amble.simulate(compass, lc1.fixed_point + np.array([1e-3, -1e-3, 0, 0]), params={"slope": slope},
                          steps=120, sample_dt=0.0)
    lc2 = find_fixed_point(compass, walk.final_post_impact_state, params={"slope": slope}, period=2)
    P = ReturnMap(compass, {"slope": slope})
    x1, _ = P(lc2.fixed_point)
    assert np.max(np.abs(x1 - lc2.fixed_point)) > 1e-3  # ...to a genuine, stable 2-cycle
    assert lc2.stable and lc2.residual < 1e-9


def test_a_guess_that_cannot_walk_is_a_typed_error(compass):
    with pytest.raises(ConvergenceError):
        find_fixed_point(compass, [0.0, 0.0, 0.1, 0.0])
