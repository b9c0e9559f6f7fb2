"""Kneed biped: impacts against conservation laws, walking, limit cycle, and Hsu Chen's published gait."""

import functools

import numpy as np
import pytest

from amble import simulate
from amble.analysis.poincare import find_fixed_point
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.simulate import parameter_vector

#: Hsu Chen (2007) Table 3.1 parameters; the slope of Tedrake's kneedCompassGait.m, asin(7.25/144) = 0.0503685 rad
#: (the thesis prints 0.0504), which is the slope of her published fixed point (docs/references.md, 3a).
HSU_CHEN = dict(mh=0.5, mt=0.5, ms=0.05, a1=0.375, b1=0.125, a2=0.175, b2=0.325, g=9.8,
                slope=float(np.arcsin(7.25 / 144)))
#: McGeer (1990) Fig. 2 in leg lengths, gyration radii as segment inertias m·r² (his round feet left out)
MCGEER = dict(mh=0.6885, mt=0.1, ms=0.062, a1=0.30, b1=0.24, a2=0.26, b2=0.20, It=0.1 * 0.135**2, Is=0.062 * 0.186**2,
              slope=0.0456)
#: the model's default parameters (segment inertias zero: point masses, as in Hsu Chen's walker)
DEFAULTS = dict(mh=10.0, mt=3.5, ms=1.5, a1=0.25, b1=0.25, a2=0.15, b2=0.35, g=9.81, slope=0.05)
#: her published fixed point [q1, q2 = q3, q1', q2' = q3'] (code's default x0), Goswami's signs: ours = −hers
HSU_CHEN_X0 = np.array([0.187700106303669, -0.288437140111164, -1.101439041094875, -0.039885255927632])


@pytest.fixture(scope="module")
def kneed():
    return load("kneed-biped")


def to_ours(x):
    """Hsu Chen's [q1, q2 = q3, q1', q2' = q3'] → our post-impact (stance, shank, thigh, velocities)."""
    return -np.array([x[0], x[1], x[1], x[2], x[3], x[3]])


def momenta(system, k, p, mode, x, about=None, swing_only=False):
    """Angular momentum (y component, kg·m²/s) about the named point's position (or the origin) of
    the whole robot or of its swing leg — point masses ``r × m v`` plus segment spins ``I ω`` —
    and the kinetic energy (J)."""
    values = dict(zip(k.meta["params"], p))
    pos, vel = k.kinematics_rows([0.0], [k.mode_index(mode)], x, p)
    names = k.meta["points"]
    o = pos[0][names.index(about)] if about else np.zeros(3)
    h = 0.0
    for name, mass in system.modes[mode].masses.items():
        if not swing_only or name.startswith("swing"):
            r, v = pos[0][names.index(name)] - o, vel[0][names.index(name)]
            h += float(mass.subs({s: values[str(s)] for s in mass.free_symbols})) * (r[2] * v[0] - r[0] * v[2])
    n = len(system.modes[mode].q)
    rates = x[n:] if mode == "unlocked" else x[[n, n + 1, n + 1]]  # stance, shank, thigh
    h += values["Is"] * rates[1] + values["It"] * rates[2]
    if not swing_only:
        h += (values["It"] + values["Is"]) * rates[0]
    return h, k.energy_rows([0.0], [k.mode_index(mode)], x, p)[0, 0]


def random_states(rng, n, constrained):
    """Post-heel-strike-like states: shank = thigh when ``constrained`` (the knee-lock guard)."""
    for _ in range(n):
        q = rng.uniform(-0.5, 0.5, 3)
        if constrained:
            q[1] = q[2]
        yield np.concatenate([q, rng.uniform(-3, 3, 3)])


@pytest.mark.parametrize("params", [None, HSU_CHEN, MCGEER])
def test_knee_lock_conserves_momenta_and_never_adds_energy(kneed, params):
    # The knee impulse is internal to the swing leg, which hangs from the hip; the only external
    # impulse on the robot acts at the stance foot.
    k = compiled(kneed)
    p = parameter_vector(k, params)
    for x in random_states(np.random.default_rng(3), 40, constrained=True):
        mode, post = k.reset("knee_lock", 0.0, x, p)
        assert mode == "locked"
        assert post[1] == x[2] and post[0] == x[0]
        for about, swing_only in (("hip", True), (None, False)):
            h0, e0 = momenta(kneed, k, p, "unlocked", x, about, swing_only)
            h1, e1 = momenta(kneed, k, p, "locked", post, about, swing_only)
            assert abs(h1 - h0) <= 1e-12 * max(1.0, abs(h0))
        assert e1 <= e0 * (1 + 1e-12)


@pytest.mark.parametrize("params", [None, HSU_CHEN, MCGEER])
def test_heel_strike_conserves_angular_momentum_about_the_impact_point(kneed, params):
    k = compiled(kneed)
    p = parameter_vector(k, params)
    rng = np.random.default_rng(5)
    for _ in range(40):
        x = np.concatenate([rng.uniform(-0.5, 0.5, 2), rng.uniform(-3, 3, 2)])
        mode, post = k.reset("heel_strike", 0.0, x, p)
        assert mode == "unlocked"
        assert np.array_equal(post[:3], x[[1, 0, 0]])  # thesis Eq. 29
        assert post[4] == post[5]  # the new swing leg leaves the ground straight
        h0, e0 = momenta(kneed, k, p, "locked", x, about="swing_foot")
        h1, e1 = momenta(kneed, k, p, "unlocked", post)  # the new stance foot is the new origin
        assert abs(h1 - h0) <= 1e-12 * max(1.0, abs(h0))
        assert e1 <= e0 * (1 + 1e-12)


def test_walks_fifty_steps_from_the_default_start(kneed):
    tr = simulate(kneed, steps=50)
    assert tr.status == "completed" and tr.steps == 50
    # every step is a knee lock followed by a heel strike
    assert [e.name for e in tr.events[:4]] == ["knee_lock", "heel_strike"] * 2
    # and the swing foot clears the slope all along (no scuff behind the stance foot goes unnoticed)
    foot = tr.points()["swing_foot"]
    assert np.nanmin(np.sin(0.05) * foot[:, 0] + np.cos(0.05) * foot[:, 2]) > -1e-9


def test_default_limit_cycle_is_stable(kneed):
    lc = find_fixed_point(kneed)
    assert lc.residual < 1e-9 and lc.stable
    st, sh, th = lc.fixed_point[:3]
    # on the section: both feet on the slope (legs symmetric about its normal) and a straight swing knee
    assert st + sh == pytest.approx(2 * 0.05, abs=1e-9) and sh == th and lc.fixed_point[4] == lc.fixed_point[5]
    # the same walker at the model's defaults (It = Is = 0: point masses, as hers) integrated by
    # the SciPy oracle, from Newton started at the model's stored gait (her signs: ours = −hers)
    x = np.asarray(kneed.default_start["unlocked"])
    ref = _oracle(DEFAULTS["slope"], (-x[0], -x[3], -x[5]), DEFAULTS)
    np.testing.assert_allclose(lc.fixed_point, _hers_to_ours(ref["fixed_point"]), rtol=0, atol=1e-9)
    assert lc.step_time == pytest.approx(ref["step_time"], abs=1e-9)
    key = lambda z: (abs(z), z.imag)  # noqa: E731
    np.testing.assert_allclose(sorted(lc.multipliers, key=key), sorted(ref["multipliers"], key=key), atol=1e-6)


def euler_stride(k, p, x, dt=1e-3):
    """One stride with Hsu Chen's integrator (Tedrake's kneedCompassGait.m): forward Euler at ``dt``;
    a crossing inside a step is located by halving the step down to 1e-20 s, advancing by
    Euler sub-steps while not yet crossed; the knee locks at the last such point (or the first
    crossed one if none) and the heel strikes one point earlier (the code drops the last point).
    Our derived equations and resets."""
    gamma = p[k.meta["params"].index("slope")]
    crossed = {"unlocked": lambda y: y[1] < y[2], "locked": lambda y: y[0] + y[1] >= 2 * gamma}
    mode = "unlocked"
    for _ in range(int(5 / dt)):
        xn = x + dt * k.rhs(mode, 0.0, x, p)
        if crossed[mode](xn) and (mode == "unlocked" or xn[0] > xn[1]):
            points, h = [x], dt
            while h > 1e-20:
                h /= 2
                y = points[-1] + h * k.rhs(mode, 0.0, points[-1], p)
                if not crossed[mode](y):
                    points.append(y)
            if mode == "locked":
                return k.reset("heel_strike", 0.0, points[-2] if len(points) > 2 else [x, xn][len(points) - 1], p)[1]
            mode, xn = k.reset("knee_lock", 0.0, points[-1] if len(points) > 1 else xn, p)
        x = xn
    raise AssertionError("no heel strike within 5 s")


def test_hsu_chen_published_fixed_point_is_that_of_her_euler_scheme(kneed):
    # Our derived dynamics and impacts, stepped with her dt = 1e-3 Euler scheme, map her published
    # fixed point to itself: the equations agree with hers, and her numbers carry the Euler error.
    k = compiled(kneed)
    p = parameter_vector(k, HSU_CHEN)
    x0 = to_ours(HSU_CHEN_X0)
    np.testing.assert_allclose(euler_stride(k, p, x0), x0, rtol=0, atol=1e-9)


def _oracle(slope: float, z0: tuple = (0.1877, -1.1014, -0.0399), params: dict | None = None) -> dict:
    """Hsu Chen's walker integrated by SciPy from equations written out independently of amble
    (tests/oracles/kneed_biped.py), with her parameters or ``params``, on ``slope``: her signs,
    post-heel-strike state [q1, q2, q3, q1', q2', q3']."""
    return _oracle_cached(slope, tuple(float(v) for v in z0), tuple(sorted((params or HSU_CHEN).items())))


@functools.cache
def _oracle_cached(slope: float, z0: tuple, params: tuple) -> dict:
    from oracles.kneed_biped import limit_cycle

    return limit_cycle(dict(dict(params), slope=slope), z0)


def _hers_to_ours(x):
    """Her full post-heel-strike state [q1, q2, q3, q1', q2', q3'] → ours (stance, shank, thigh, rates)."""
    return -np.asarray(x)[[0, 2, 1, 3, 5, 4]]


def test_hsu_chen_accurate_limit_cycle(kneed):
    # against her walker integrated by SciPy (DOP853 at 1e-12, Newton with central differences):
    # [q1, q1', q2'] = [0.18816565, -1.10894729, -0.05771783], step 0.564578 s, multipliers
    # 0.35314 ± 0.55211i and 0.14387 (docs/references.md 3a)
    ref = _oracle(HSU_CHEN["slope"])
    lc = find_fixed_point(kneed, to_ours(HSU_CHEN_X0), params=HSU_CHEN)
    assert lc.residual < 1e-9 and lc.stable
    np.testing.assert_allclose(lc.fixed_point, _hers_to_ours(ref["fixed_point"]), rtol=0, atol=1e-8)
    assert lc.step_time == pytest.approx(ref["step_time"], abs=1e-8)
    knee = next(e for e in lc.trajectory(steps=1).events if e.name == "knee_lock")
    assert knee.t == pytest.approx(ref["knee_time"], abs=1e-8)
    # the oracle's multipliers carry central-difference errors of ~1e-8
    key = lambda z: (abs(z), z.imag)  # noqa: E731
    np.testing.assert_allclose(sorted(lc.multipliers, key=key), sorted(ref["multipliers"], key=key), atol=1e-6)
    # the published (Euler, dt = 1e-3) numbers are off by 0.018 rad/s in the swing velocity
    assert np.max(np.abs(lc.fixed_point - to_ours(HSU_CHEN_X0))) == pytest.approx(0.0179, abs=5e-4)


@pytest.mark.slow
def test_hsu_chen_euler_fixed_point_converges_to_the_accurate_one_at_first_order(kneed):
    k = compiled(kneed)
    p = parameter_vector(k, HSU_CHEN)
    exact = find_fixed_point(kneed, to_ours(HSU_CHEN_X0), params=HSU_CHEN).fixed_point
    errors = []
    for dt in (1e-3, 2.5e-4):
        x = to_ours(HSU_CHEN_X0)
        for _ in range(60):  # |multipliers| ≤ 0.66: 60 strides converge to ~1e-11
            x = euler_stride(k, p, x, dt)
        errors.append(np.max(np.abs(x - exact)))
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.25)


#: the three slopes of Hsu Chen's parameters: her code's asin(7.25/144), her thesis' 0.0504, and 0.06
HSU_CHEN_SLOPES = [float(np.arcsin(7.25 / 144)), 0.0504, 0.06]


@pytest.mark.parametrize("slope", [*HSU_CHEN_SLOPES, 0.04, 0.07])
def test_default_search_finds_the_stable_gait_at_hsu_chens_parameters(kneed, slope):
    params = dict(HSU_CHEN, slope=slope)
    lc = find_fixed_point(kneed, params=params)
    assert lc.residual < 1e-9 and lc.stable
    # stable in fact, not only by its multipliers: a perturbed walker returns to the cycle
    tr = simulate(kneed, lc.fixed_point + np.array([0.0, 0.0, 0.0, 0.02, -0.03, -0.03]), params=params, steps=40)
    assert tr.status == "completed"
    np.testing.assert_allclose(tr.final_post_impact_state, lc.fixed_point, atol=1e-5)
    if slope in (HSU_CHEN_SLOPES[0], 0.06):  # the SciPy oracle's stable gait (tests/oracles/kneed_biped.py)
        # at 0.06 not the unstable gait of 0.474 s, |μ| 3.60, that lies nearer the model's default gait
        ref = _oracle(slope)
        assert lc.step_time == pytest.approx(ref["step_time"], abs=1e-8)
        np.testing.assert_allclose(lc.fixed_point, _hers_to_ours(ref["fixed_point"]), rtol=0, atol=1e-8)


def test_an_explicit_guess_is_followed_even_to_an_unstable_gait(kneed):
    # the unstable cycle at slope 0.06 exists; a guess near it finds it (the search does not
    # swap a cycle the caller asked for)
    guess = [-0.18746, 0.30746, 0.30746, 1.32788, 0.50149, 0.50149]
    lc = find_fixed_point(kneed, guess, params=dict(HSU_CHEN, slope=0.06))
    # the SciPy oracle's Newton from the same guess (her signs) finds the same unstable gait
    ref = _oracle(0.06, (0.18746, -1.32788, -0.50149))
    assert not lc.stable and lc.step_time == pytest.approx(ref["step_time"], abs=1e-8)
    np.testing.assert_allclose(lc.fixed_point, _hers_to_ours(ref["fixed_point"]), rtol=0, atol=1e-8)
    assert max(abs(lc.multipliers)) == pytest.approx(max(abs(ref["multipliers"])), rel=1e-6)
    assert max(abs(lc.multipliers)) > 3  # ≈ 3.60
