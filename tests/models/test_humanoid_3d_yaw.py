"""The 3D humanoid against conservation laws at the impact, its walking, and its limit cycle
against the same robot written out independently (tests/oracles/humanoid_3d_yaw.py)."""

import numpy as np
import pytest

from amble import simulate
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.simulate import parameter_vector

MIRROR = np.array([-1.0, 1.0, -1.0])  # angular momentum (a pseudovector) under the y → −y relabel


@pytest.fixture(scope="module")
def humanoid():
    return load("humanoid-3d-yaw")


@pytest.fixture(scope="module")
def cycle(humanoid):
    from amble.analysis.poincare import find_fixed_point

    return find_fixed_point(humanoid)


def _frame(q):
    """Upper-body orientation Ry(torso)·Rx(−torso_cor)·Rz(yaw), written out independently in numpy."""
    t, c, y = q[4], -q[5], q[6]
    ry = np.array([[np.cos(t), 0, np.sin(t)], [0, 1, 0], [-np.sin(t), 0, np.cos(t)]])
    rx = np.array([[1, 0, 0], [0, np.cos(c), -np.sin(c)], [0, np.sin(c), np.cos(c)]])
    rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    return ry @ rx @ rz


def _momentum(k, p, x, about):
    """Angular momentum (kg·m²/s, world axes) about ``about``: point masses plus the upper body's spin R·I·ω."""
    pos, vel = k.kinematics_rows([0.0], [0], x, p)
    names = k.meta["points"]
    par = dict(zip(k.meta["params"], p))
    masses = {"hip": par["mh"], "stance_mass": par["m"], "swing_mass": par["m"], "torso": par["mt"]}
    h = sum(m * np.cross(pos[0][names.index(n)] - about, vel[0][names.index(n)]) for n, m in masses.items())
    q, qd, eps = x[:7], x[7:], 1e-6
    R = _frame(q)
    W = R.T @ (_frame(q + eps * qd) - _frame(q - eps * qd)) / (2 * eps)  # [ω]ₓ in body axes
    omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
    return h + R @ (np.diag([par["I_xy"], par["I_xy"], par["I_z"]]) @ omega)


def test_impact_conserves_3d_angular_momentum_and_never_adds_energy(humanoid):
    k = compiled(humanoid)
    p = parameter_vector(k, None)
    names = k.meta["points"]
    rng = np.random.default_rng(3)
    for _ in range(50):
        x = np.concatenate([rng.uniform(-0.4, 0.4, 7), rng.uniform(-2, 2, 7)])
        _, post = k.reset("heel_strike", 0.0, x, p)
        foot = k.kinematics_rows([0.0], [0], x, p)[0][0][names.index("swing_foot")]
        h0 = _momentum(k, p, x, foot)
        h1 = MIRROR * _momentum(k, p, post, np.zeros(3))  # new stance foot at the origin, y mirrored
        assert np.allclose(h1, h0, rtol=0, atol=1e-10 * max(1.0, np.abs(h0).max()))  # ω by central differences
        e0 = k.energy_rows([0.0], [0], x, p)[0, 0]
        e1 = k.energy_rows([0.0], [0], post, p)[0, 0]
        assert e1 <= e0 * (1 + 1e-12)


def test_the_oracles_leg_swap_is_the_mirror_image():
    """The oracle's relabelling is geometry, not a copy of the model's: after its swap every
    point, seen from the new stance foot, is the mirror image (y → −y) of its old partner seen
    from the old swing foot."""
    from oracles.humanoid_3d_yaw import PARAMS, impact, points

    partner = {"stance_mass": "swing_mass", "hip": "hip", "swing_mass": "stance_mass", "torso": "torso"}
    flip = np.array([1.0, -1.0, 1.0])  # a position under y → −y
    rng = np.random.default_rng(5)
    for _ in range(10):
        x = np.concatenate([rng.uniform(-0.4, 0.4, 7), rng.uniform(-2, 2, 7)])
        old, new = points(x), points(impact(x, PARAMS))
        for name, was in partner.items():
            np.testing.assert_allclose(new[name], flip * (old[was] - old["swing_foot"]), atol=1e-14)
        np.testing.assert_allclose(new["swing_foot"], -flip * old["swing_foot"], atol=1e-14)


def test_walks_50_steps_with_bounded_sway(humanoid):
    tr = simulate(humanoid, steps=50)
    assert tr.status == "completed" and tr.steps == 50
    sway = np.abs(np.array([e.x_post[2] for e in tr.step_events]))  # stance coronal angle after each step
    assert sway.max() < 0.1


def test_upright_sagittal_start_is_attracted_to_the_gait(humanoid, cycle):
    # the humanoid-2d gait with every coronal angle and the yaw at zero: a different state that a
    # stable cycle must pull onto its fixed point (the one the SciPy oracle confirms below)
    x0 = [-0.2206, 0.3206, 0, 0, -0.0442, 0, 0, 0.971, 0.411, 0, 0, 0.464, 0, 0]
    tr = simulate(humanoid, x0, steps=50, sample_dt=0.0)
    assert tr.status == "completed"
    assert np.allclose(tr.final_post_impact_state, cycle.fixed_point, atol=1e-6)
    # and the model's stored start is that gait
    assert np.allclose(humanoid.default_start["humanoid-3d-yaw"], cycle.fixed_point, atol=1e-8)


def test_stable_limit_cycle_is_a_fixed_point_of_the_independent_step_map(cycle):
    """The robot's equations formed by Kane's method and its impact by the extended-coordinate
    plastic impact, integrated by SciPy (DOP853 at 1e-12): amble's fixed point maps to itself in
    the same time, and the map's multipliers (central differences of the 14-D map) are amble's."""
    from oracles.humanoid_3d_yaw import jacobian, step

    assert cycle.residual < 1e-9
    assert cycle.stable and np.all(np.abs(cycle.multipliers) < 1)
    nxt, period = step(cycle.fixed_point)
    # amble's residual is ~1e-12; with |multipliers| ≤ 0.53 a residual r puts the fixed point
    # within r / (1 − 0.53) of the oracle's
    assert np.max(np.abs(nxt - cycle.fixed_point)) < 1e-9
    assert period == pytest.approx(cycle.step_time, abs=1e-9)
    assert abs(cycle.fixed_point).max() > 0.5  # a gait, not the rest state
    ours = cycle.multipliers[np.abs(cycle.multipliers) > 1e-6]
    mu = np.linalg.eigvals(jacobian(cycle.fixed_point))
    ref = mu[np.abs(mu) > 1e-6]  # the rest are zero up to the differences' error (~1e-8)
    assert len(ours) == len(ref) == 10
    # the differences carry errors of ~1e-6 (the integration tolerance over a 1e-6 step)
    np.testing.assert_allclose(np.sort_complex(ours), np.sort_complex(ref), rtol=0, atol=1e-5)
