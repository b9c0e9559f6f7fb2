"""The thesis' 3D humanoid (knee, seven coordinates) against conservation laws, and its gait against the
2D robot written out independently (tests/oracles/humanoid_2d.py).

Angular momenta are computed here from the compiled kinematics (positions and velocities of the
named points) and the masses written out below, with numpy: they are not quantities the model or
the derivation provides.
"""

import numpy as np
import pytest

from amble import simulate
from amble.analysis.poincare import find_fixed_point
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.simulate import parameter_vector

MIRROR = np.array([-1.0, 1.0, -1.0])  # angular momentum (a pseudovector) under the y → −y relabel
SWING_LEG = ("swing_thigh", "swing_shank")
PASSIVE = dict.fromkeys(["kT", "kv", "kleg", "k_sc", "kv_sc", "k_sw", "kv_sw", "k_tc", "kv_tc"], 0.0)


@pytest.fixture(scope="module")
def humanoid():
    return load("humanoid-3d")


@pytest.fixture(scope="module")
def kernels(humanoid):
    return compiled(humanoid)


def _masses(par):
    return {"stance_shank": par["ms"], "stance_thigh": par["mt"], "hip": par["mh"], "swing_thigh": par["mt"],
            "swing_shank": par["ms"], "torso": par["mT"]}


def _momentum(k, p, mode, x, about, only=None):
    """Angular momentum (kg·m²/s, world axes) of the point masses (or of ``only``) about a point
    (a point name or coordinates)."""
    pos, vel = k.kinematics_rows([0.0], [k.mode_index(mode)], x, p)
    names = k.meta["points"]
    o = pos[0][names.index(about)] if isinstance(about, str) else np.asarray(about, float)
    masses = _masses(dict(zip(k.meta["params"], p)))
    return sum(mass * np.cross(pos[0][names.index(n)] - o, vel[0][names.index(n)])
               for n, mass in masses.items() if only is None or n in only)


def _kinetic(k, p, mode, x):
    return k.energy_rows([0.0], [k.mode_index(mode)], x, p)[0, 0]


def test_heel_strike_conserves_all_three_components_of_angular_momentum(kernels):
    k = kernels
    p = parameter_vector(k, None)
    rng = np.random.default_rng(5)
    for _ in range(40):
        x = np.concatenate([rng.uniform(-0.5, 0.5, 6), rng.uniform(-3, 3, 6)])  # mode "locked"
        mode, post = k.reset("heel_strike", 0.0, x, p)
        assert mode == "unlocked"
        h0 = _momentum(k, p, "locked", x, "swing_foot")
        h1 = MIRROR * _momentum(k, p, "unlocked", post, np.zeros(3))  # new stance foot at the origin
        assert np.allclose(h1, h0, rtol=0, atol=1e-11 * max(1.0, np.abs(h0).max()))
        assert _kinetic(k, p, "unlocked", post) <= _kinetic(k, p, "locked", x) + 1e-12


def test_knee_lock_conserves_angular_momenta_about_the_foot_and_of_the_swing_leg_about_the_hip(kernels):
    k = kernels
    p = parameter_vector(k, None)
    rng = np.random.default_rng(7)
    for _ in range(40):
        q = rng.uniform(-0.5, 0.5, 7)
        q[3] = q[2]  # shank = thigh: on the knee-lock guard
        x = np.concatenate([q, rng.uniform(-3, 3, 7)])
        mode, post = k.reset("knee_lock", 0.0, x, p)
        assert mode == "locked"
        for about, only in (("stance_foot", None), ("hip", SWING_LEG)):
            h0 = _momentum(k, p, "unlocked", x, about, only)
            h1 = _momentum(k, p, "locked", post, about, only)
            assert np.allclose(h1, h0, rtol=0, atol=1e-11 * max(1.0, np.abs(h0).max()))
        assert _kinetic(k, p, "locked", post) <= _kinetic(k, p, "unlocked", x) + 1e-12


def test_energy_is_conserved_between_impacts_without_control(humanoid):
    # a 3D swing from a sideways-leaning start, every gain zero: no force but gravity does work
    x0 = [-0.2, 0.03, 0.3, 0.35, -0.02, 0.05, 0.04, 1.0, -0.1, 0.4, 0.2, 0.3, 0.2, -0.1]
    tr = simulate(humanoid, x0, params=PASSIVE, t_end=0.3, sample_dt=0.005)
    first = tr.events[0].t if tr.events else tr.t[-1]
    e = tr.energy().sum(axis=1)[tr.t < first]
    assert len(e) > 10 and np.ptp(e) < 1e-8 * np.abs(e).max()


def test_stable_limit_cycle_with_a_knee(humanoid):
    lc = find_fixed_point(humanoid)
    assert lc.residual < 1e-9 and lc.stable
    assert np.all(np.abs(lc.multipliers) < 1)
    tr = simulate(humanoid, lc.fixed_point, steps=1, sample_dt=0.0)
    assert [e.name for e in tr.events] == ["knee_lock", "heel_strike"]  # the knee locks before heel strike
    # left–right symmetric: the gait is the 2D humanoid's with every coronal angle and rate zero,
    # which the 2D robot written out independently and integrated by SciPy maps to itself
    from oracles.humanoid_2d import jacobian, step

    x = lc.fixed_point
    coronal = [1, 4, 6, 8, 11, 13]
    assert np.max(np.abs(x[coronal])) < 1e-12
    planar = x[[0, 3, 2, 5, 7, 10, 9, 12]]  # (stance, shank, thigh, torso) and their rates
    nxt, t_knee, t_step = step(planar)
    assert np.max(np.abs(nxt - planar)) < 1e-9 and t_step == pytest.approx(lc.step_time, abs=1e-9)
    assert t_knee == pytest.approx(tr.events[0].t, abs=1e-9)
    # and the sagittal multipliers are among the 3D ones
    mu = np.linalg.eigvals(jacobian(planar))
    for m in mu[np.abs(mu) > 0.01]:
        assert np.min(np.abs(lc.multipliers - m)) < 1e-6


def test_a_sideways_lean_and_sway_die_out(humanoid):
    x0 = np.array(humanoid.fixed_point_guess)
    x0[[1, 4, 6, 8, 11, 13]] += [0.03, -0.02, 0.05, -0.2, 0.3, 0.2]  # coronal angles and rates
    tr = simulate(humanoid, x0, steps=30, sample_dt=0.0)
    assert tr.status == "completed"
    assert np.max(np.abs(tr.final_post_impact_state[[1, 4, 6, 8, 11, 13]])) < 1e-6


def test_without_the_stance_roll_spring_the_sideways_fall_is_unstable(humanoid):
    lc = find_fixed_point(humanoid, params={"k_sc": 0.0})
    assert not lc.stable and np.sum(np.abs(lc.multipliers) > 1) == 1
