"""Humanoid 2D: impacts against conservation laws, the controlled gait against the same robot
written out independently (tests/oracles/humanoid_2d.py), and the step-length torque."""

import numpy as np
import pytest

from amble import simulate
from amble.analysis.poincare import find_fixed_point
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.simulate import parameter_vector


@pytest.fixture(scope="module")
def humanoid():
    return load("humanoid-2d")


def momenta(system, k, p, mode, x, about=None, points=None):
    """Angular momentum (y component, kg·m²/s) of the point masses (optionally only ``points``)
    about the named point's position (or the origin), and the kinetic energy (J)."""
    values = dict(zip(k.meta["params"], p))
    pos, vel = k.kinematics_rows([0.0], [k.mode_index(mode)], x, p)
    names = k.meta["points"]
    o = pos[0][names.index(about)] if about else np.zeros(3)
    h = 0.0
    for name, mass in system.modes[mode].masses.items():
        if points is None or name in points:
            r, v = pos[0][names.index(name)] - o, vel[0][names.index(name)]
            h += float(mass.subs({s: values[str(s)] for s in mass.free_symbols})) * (r[2] * v[0] - r[0] * v[2])
    return h, k.energy_rows([0.0], [k.mode_index(mode)], x, p)[0, 0]


def test_knee_lock_conserves_momenta_and_never_adds_energy(humanoid):
    k = compiled(humanoid)
    p = parameter_vector(k, None)
    rng = np.random.default_rng(11)
    for _ in range(30):
        q = rng.uniform(-0.5, 0.5, 4)
        q[1] = q[2]  # on the knee-lock guard
        x = np.concatenate([q, rng.uniform(-3, 3, 4)])
        mode, post = k.reset("knee_lock", 0.0, x, p)
        assert mode == "locked" and np.array_equal(post[:3], x[[0, 2, 3]])
        for about, pts in (("hip", {"swing_thigh", "swing_shank"}), (None, None)):
            h0, e0 = momenta(humanoid, k, p, "unlocked", x, about, pts)
            h1, e1 = momenta(humanoid, k, p, "locked", post, about, pts)
            assert abs(h1 - h0) <= 1e-12 * max(1.0, abs(h0))
        assert e1 <= e0 * (1 + 1e-12)


def test_heel_strike_conserves_angular_momentum_about_the_impact_point(humanoid):
    k = compiled(humanoid)
    p = parameter_vector(k, None)
    rng = np.random.default_rng(13)
    for _ in range(30):
        x = np.concatenate([rng.uniform(-0.5, 0.5, 3), rng.uniform(-3, 3, 3)])
        mode, post = k.reset("heel_strike", 0.0, x, p)
        assert mode == "unlocked" and np.array_equal(post[:4], x[[1, 0, 0, 2]])  # torso angle kept
        h0, e0 = momenta(humanoid, k, p, "locked", x, about="swing_foot")
        h1, e1 = momenta(humanoid, k, p, "unlocked", post)
        assert abs(h1 - h0) <= 1e-12 * max(1.0, abs(h0))
        assert e1 <= e0 * (1 + 1e-12)


def test_walks_fifty_steps_from_the_default_start(humanoid):
    tr = simulate(humanoid, steps=50)
    assert tr.status == "completed" and tr.steps == 50
    torso = tr.column("torso")
    assert np.nanmax(np.abs(torso)) < 0.2  # the PD keeps the torso near upright (rad)
    foot = tr.points()["swing_foot"]  # the swing foot clears the slope all along
    assert np.nanmin(np.sin(0.05) * foot[:, 0] + np.cos(0.05) * foot[:, 2]) > -1e-9


def test_default_limit_cycle_is_stable(humanoid):
    lc = find_fixed_point(humanoid)
    assert lc.residual < 1e-9 and lc.stable
    st, sh, th = lc.fixed_point[:3]
    assert st + sh == pytest.approx(2 * 0.05, abs=1e-9) and sh == th
    # the same robot by Kane's equations, its knee lock and heel strike, integrated by SciPy
    # (DOP853 at 1e-12): amble's fixed point maps to itself, with amble's event times
    from oracles.humanoid_2d import jacobian, step

    nxt, t_knee, t_step = step(lc.fixed_point)
    assert np.max(np.abs(nxt - lc.fixed_point)) < 1e-9
    assert t_step == pytest.approx(lc.step_time, abs=1e-9)
    knee = next(e for e in lc.trajectory(steps=1).events if e.name == "knee_lock")
    assert t_knee == pytest.approx(knee.t, abs=1e-9)
    # and the map's multipliers (central differences of the 6-D map; one of them is the section's 0)
    mu = np.linalg.eigvals(jacobian(lc.fixed_point))
    ref = mu[np.argsort(-np.abs(mu))][:len(lc.multipliers)]
    assert len(lc.multipliers) == 5 and np.abs(mu).min() < 1e-6
    np.testing.assert_allclose(np.sort_complex(lc.multipliers), np.sort_complex(ref), rtol=0, atol=1e-6)
    # the model's stored start is this gait
    np.testing.assert_allclose(lc.fixed_point, humanoid.default_start["unlocked"], atol=1e-9)


def test_step_length_torque_does_the_work_of_eq_35(humanoid):
    # Work–energy: the power of τ₂ = −k_leg L on the swing thigh is τ₂·thigh_dot for
    # L = −x(swing foot) > 0 and zero once the swing foot is ahead (thesis Eq. 35); it is the
    # difference of dE/dt with and without the torque (the PD torque's power cancels).
    k = compiled(humanoid)
    kleg = 5.0
    on, off = parameter_vector(k, {"kleg": kleg}), parameter_vector(k, {"kleg": 0.0})
    foot = k.meta["points"].index("swing_foot")

    def power(x, p, h=1e-6):
        f = k.rhs("unlocked", 0.0, x, p)
        e = k.energy_rows([0.0, 0.0], [0, 0], np.array([x + h * f, x - h * f]), p).sum(axis=1)
        return (e[0] - e[1]) / (2 * h)

    for x in ([-0.1, 0.3, 0.3, 0.05, 1.0, 0.5, 0.7, -0.3], [0.2, -0.15, -0.15, 0.0, 1.0, -0.5, -0.4, 0.2]):
        x = np.array(x)
        L = -k.kinematics_rows([0.0], [0], x, on)[0][0, foot, 0]
        expected = -kleg * L * x[6] if L > 0 else 0.0
        assert power(x, on) - power(x, off) == pytest.approx(expected, abs=1e-7)


def test_multipliers_do_not_depend_on_where_newton_stopped(humanoid):
    """Exact Jacobians: multipliers from two states 1e-11 apart on the cycle agree to 1e-9 (with
    central differences of step 1e-5 they moved by ~7e-7)."""
    from amble.analysis.poincare import ReturnMap

    lc = find_fixed_point(humanoid)
    P = ReturnMap(humanoid)
    mus = [np.sort_complex(np.linalg.eigvals(P.section_jacobian(lc.fixed_point + dx)[0])) for dx in (0.0, 1e-11)]
    assert np.max(np.abs(mus[0] - mus[1])) < 1e-9
    # and they agree with central differences to the differences' own error
    fd = np.sort_complex(np.linalg.eigvals(P.section_jacobian(lc.fixed_point, "fd")[0]))
    assert np.max(np.abs(fd - mus[0])) < 1e-5
