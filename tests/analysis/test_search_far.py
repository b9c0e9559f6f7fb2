"""Gaits found far from the models' defaults, checked against independent implementations
(tests/oracles/round_foot_walker.py, tests/oracles/compass_gait.py): each oracle's own Newton,
started off amble's gait, must converge to the same fixed point, step time and multipliers."""

import numpy as np
import pytest

from amble.analysis.homotopy import time_scaling
from amble.analysis.poincare import ReturnMap, find_fixed_point
from amble.errors import ConvergenceError
from amble.models import load

RFW_DEFAULTS = dict(mh=10.0, m=5.0, I=0.2042, l=0.7, c=0.35, r=0.3, g=9.81, slope=0.05)
# every parameter at least 30 % from its default, gravity among them
RFW_FAR = [dict(mh=1000.0, m=1.0, I=0.0, l=1.0, c=1.0, r=0.0, g=1.0, slope=0.009),
           dict(mh=20.0, m=2.0, I=0.05, l=1.0, c=0.5, r=0.15, g=3.7, slope=0.03),
           dict(mh=2.0, m=1.0, I=0.1, l=0.95, c=0.6, r=0.45, g=1.62, slope=0.02)]


def _largest(mu, k):
    return sorted(np.asarray(mu)[np.argsort(-np.abs(mu))][:k], key=lambda z: (round(abs(z), 6), z.imag))


@pytest.mark.parametrize("far", RFW_FAR, ids=["heavy-hip-g1", "mars", "moon"])
def test_round_foot_walker_far_from_its_defaults(far):
    from oracles.round_foot_walker import fixed_point

    assert all(abs(far[k] - v) >= 0.3 * v for k, v in RFW_DEFAULTS.items())
    lc = find_fixed_point(load("round-foot-walker"), params=far)
    assert lc.stable and lc.residual < 1e-12
    x, T, mu = fixed_point(far, lc.fixed_point + 1e-4 * np.array([1, -1, 1, 1]))
    np.testing.assert_allclose(lc.fixed_point, x, rtol=0, atol=1e-9)
    assert lc.step_time == pytest.approx(T, abs=1e-9)
    k = len(lc.multipliers)
    np.testing.assert_allclose(_largest(lc.multipliers, k), _largest(mu, k), atol=1e-6)


COMPASS_FAR = [dict(mh=10.0, m=5.0, a=0.5, b=0.5, slope=0.03), dict(mh=20.0, m=5.0, a=0.5, b=0.5, slope=0.05),
               dict(mh=5.0, m=5.0, a=0.5, b=0.5, slope=0.04), dict(mh=10.0, m=5.0, a=0.6, b=0.4, slope=0.05),
               dict(mh=10.0, m=5.0, a=0.4, b=0.6, slope=0.05), dict(mh=10.0, m=5.0, a=0.7, b=0.7, slope=0.05),
               dict(mh=2.0, m=1.0, a=0.45, b=0.35, g=3.7, slope=0.02)]


@pytest.mark.parametrize("far", COMPASS_FAR)
def test_compass_gait_over_mass_ratio_geometry_and_slope(far):
    from oracles import compass_gait as cg

    lc = find_fixed_point(load("compass-gait"), params=far)
    xa = lc.fixed_point
    # Goswami's coordinates: (th_ns, th_s) = −(swing, stance), counter-clockwise; his a is the
    # leg's mass from the foot, ours from the hip
    par = (far["m"], far["mh"], far["b"], far["a"], far.get("g", 9.81))
    x, jac = cg.fixed_point(far["slope"], np.array([-xa[0], -xa[3], -xa[2]]) + 1e-4, par)
    np.testing.assert_allclose(xa, [-x[1], -x[0], -x[3], -x[2]], rtol=0, atol=1e-9)
    np.testing.assert_allclose(_largest(lc.multipliers, 3), _largest(np.linalg.eigvals(jac), 3), atol=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("far", COMPASS_FAR)
def test_compass_gait_against_the_oracles_own_continuation(far):
    from oracles import compass_gait as cg

    lc = find_fixed_point(load("compass-gait"), params=far)
    x, _ = cg.follow(far["slope"], (far["m"], far["mh"], far["b"], far["a"], far.get("g", 9.81)))
    np.testing.assert_allclose(lc.fixed_point, [-x[1], -x[0], -x[3], -x[2]], rtol=0, atol=1e-9)


def test_gravity_rescales_time_exactly():
    # the default gait at g is a gait at g' with velocities × √(g'/g): found on the map itself
    w = load("round-foot-walker")
    P = ReturnMap(w)
    lc = find_fixed_point(w)
    p1 = P.p.copy()
    j = list(P.k.meta["params"]).index("g")
    p1[j] = 2.5
    found = time_scaling(P, lc.fixed_point, lc.step_time, P.p.copy(), p1)
    assert found is not None and found[0] == j
    at = find_fixed_point(w, params={"g": 2.5})
    assert at.step_time == pytest.approx(lc.step_time * np.sqrt(9.81 / 2.5), rel=1e-10)
    # a change of the slope is no time scaling
    p2 = P.p.copy()
    p2[list(P.k.meta["params"]).index("slope")] = 0.06
    assert time_scaling(P, lc.fixed_point, lc.step_time, P.p.copy(), p2) is None


def test_a_fold_is_reported_with_where_it_folds():
    # the kneed biped's gait from its defaults folds at slope 0.0451521 (a multiplier +1 there):
    # no gait of that branch below it, and the message says so
    with pytest.raises(ConvergenceError, match=r"folds at slope = 0\.045152.*no gait beyond on this branch"):
        find_fixed_point(load("kneed-biped"), params={"slope": 0.03})


def test_a_sweep_keeps_its_branch_and_says_where_it_ends():
    import amble

    res = amble.sweep(load("kneed-biped"), "fixed-point", {"slope": np.linspace(0.044, 0.07, 6)},
                      scheduler="synchronous", progress=False)
    rows = sorted(res.rows, key=lambda r: float(r["slope"]))
    # below the fold at 0.0451521 there is no gait on the branch, and the row says why
    assert rows[0]["status"] == "failed" and "folds at slope = 0.04515" in rows[0]["reason"]
    ok = [r for r in rows if r["status"] == "ok"]
    assert len(ok) == 5 and len({r["branch"] for r in ok}) == 1
    assert all(r["seeded"] == "true" and r["branch_break"] == "" for r in ok[1:])
    # one branch: its step time changes smoothly (a jump to the unstable cycle would change it by ~20 %)
    T = np.array([float(r["step_time"]) for r in ok])
    assert np.all(np.diff(T) > 0) and np.max(np.abs(np.diff(T, 2))) < 0.01
