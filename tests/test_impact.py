"""The derived plastic impact against conservation laws and Goswami's published impact map."""

import numpy as np
import pytest

from amble.backend.kernels import compiled
from amble.simulation.simulate import parameter_vector


def goswami_impact(q, qd, m, mh, a, b):
    """Goswami, Thuilot & Espiau (1996), thesis Eq. 22: q̇⁺ = Q₊⁻¹ Q₋ q̇⁻ for the compass gait.

    Their state is q = (θ_ns, θ_s) (swing first), a = foot→leg-mass, b = leg-mass→hip, and
    α = (θ_ns − θ_s)/2 is half the inter-leg angle; the relabelling is part of the map.
    """
    l = a + b
    th_s, th_ns = q  # our order: stance, swing
    alpha = (th_ns - th_s) / 2
    c2 = np.cos(2 * alpha)
    Qm = np.array([[-m * a * b, -m * a * b + (mh * l**2 + 2 * m * a * l) * c2], [0.0, -m * a * b]])
    Qp = np.array([[m * b * (b - l * c2), m * l * (l - b * c2) + m * a**2 + mh * l**2], [m * b**2, -m * b * l * c2]])
    qd_ns_s = np.array([qd[1], qd[0]])
    post = np.linalg.solve(Qp, Qm @ qd_ns_s)  # (θ̇_ns⁺, θ̇_s⁺)
    return np.array([post[1], post[0]])  # back to (stance, swing)


@pytest.mark.parametrize("ab", [(0.5, 0.5), (0.3, 0.7)])
def test_derived_impact_equals_goswami(compass, ab):
    # Our model's b is the foot→mass distance and a the hip→mass distance (thesis naming),
    # i.e. Goswami's a is our b.
    a_hip, b_foot = ab
    k = compiled(compass)
    p = parameter_vector(k, {"a": a_hip, "b": b_foot})
    rng = np.random.default_rng(1)
    for _ in range(20):
        x = np.concatenate([rng.uniform(-0.5, 0.5, 2), rng.uniform(-2, 2, 2)])
        _, post = k.reset("heel_strike", 0.0, x, p)
        assert np.allclose(post[:2], x[[1, 0]], atol=0, rtol=0)  # J(q): swap (thesis Eq. 21)
        ref = goswami_impact(x[:2], x[2:], m=5.0, mh=10.0, a=b_foot, b=a_hip)
        assert np.allclose(post[2:], ref, rtol=1e-12, atol=1e-12)


def _momentum_and_energy(k, p, x, mode=0):
    pos, vel = k.kinematics_rows([0.0], [mode], x, p)
    names = k.meta["points"]
    masses = {"hip": p[k.meta["params"].index("mh")], "stance_mass": p[1], "swing_mass": p[1]}
    return pos[0], vel[0], names, masses


def test_impact_conserves_angular_momentum_and_never_adds_energy(compass):
    k = compiled(compass)
    p = parameter_vector(k, None)
    rng = np.random.default_rng(7)
    for _ in range(50):
        x = np.concatenate([rng.uniform(-0.6, 0.6, 2), rng.uniform(-3, 3, 2)])
        _, post = k.reset("heel_strike", 0.0, x, p)
        pos0, vel0, names, masses = _momentum_and_energy(k, p, x)
        pos1, vel1, _, _ = _momentum_and_energy(k, p, post)
        foot = pos0[names.index("swing_foot")]
        L0 = L1 = 0.0
        for n, m in masses.items():
            i = names.index(n)
            r0 = pos0[i] - foot
            L0 += m * (r0[2] * vel0[i][0] - r0[0] * vel0[i][2])  # y-component of r × m v
            r1 = pos1[i]  # the new stance foot is the origin after the step
            L1 += m * (r1[2] * vel1[i][0] - r1[0] * vel1[i][2])
        assert abs(L1 - L0) <= 1e-12 * max(1.0, abs(L0))
        e0 = k.energy_rows([0.0], [0], x, p)[0, 0]
        e1 = k.energy_rows([0.0], [0], post, p)[0, 0]
        assert e1 <= e0 * (1 + 1e-12)


def test_thesis_reset_written_explicitly_equals_the_derived_impact(compass):
    """The thesis' J(q) (Eq. 21) and H_g = Q₊⁻¹Q₋ (Eq. 22, Goswami's angular-momentum matrices)
    written as an Explicit reset give the same post-impact states as the derived Impact."""
    import sympy as sp

    from amble import Explicit, HybridSystem

    m = compass.modes["compass-gait"]
    st, sw = m.q
    std, swd = m.qd
    mh, ml, a, b = (m.symbol(n) for n in ("mh", "m", "a", "b"))
    l = a + b
    ga, gb = b, a  # Goswami's a (foot→mass) and b (mass→hip) in the thesis' naming
    c2 = sp.cos(sw - st)
    Qm = sp.Matrix([[-ml * ga * gb, -ml * ga * gb + (mh * l**2 + 2 * ml * ga * l) * c2], [0, -ml * ga * gb]])
    Qp = sp.Matrix([[ml * gb * (gb - l * c2), ml * l * (l - gb * c2) + ml * ga**2 + mh * l**2],
                    [ml * gb**2, -ml * gb * l * c2]])
    J = sp.Matrix([[0, 1], [1, 0]])
    Hg = J * Qp.inv() * Qm * J  # in (stance, swing) order on both sides
    explicit = HybridSystem("cg-explicit", {"compass-gait": m})
    explicit.transition("heel_strike", "compass-gait", compass.transitions[0].guard,
                        Explicit(q=J * sp.Matrix([st, sw]), qd=Hg * sp.Matrix([std, swd])), step=True)
    k1, k2 = compiled(compass), compiled(explicit)
    p = parameter_vector(k1, {"a": 0.45, "b": 0.55})
    rng = np.random.default_rng(3)
    for _ in range(10):
        x = np.concatenate([rng.uniform(-0.5, 0.5, 2), rng.uniform(-2, 2, 2)])
        assert np.allclose(k1.reset("heel_strike", 0, x, p)[1], k2.reset("heel_strike", 0, x, p)[1],
                           rtol=1e-12, atol=1e-12)


def test_dynamics_kernel_matches_the_symbolic_equations(compass):
    from amble import derive

    m = compass.modes["compass-gait"]
    eq = derive(m)
    k = compiled(compass)
    p = parameter_vector(k, None)
    x = np.array([0.1, -0.2, 0.7, -1.3])
    M, h, G = k.dynamics(0, 0.0, x, p)
    subs = dict(zip([*m.q, *m.qd], x)) | {s: v for s, v in zip(m.params, p)}
    assert np.allclose(M, np.array(eq.M.subs(subs), dtype=float), rtol=1e-13)
    assert np.allclose(h, np.array(eq.h.subs(subs), dtype=float).ravel(), rtol=1e-13)
    assert np.allclose(G, 0.0)
    qdd = k.rhs(0, 0.0, x, p)[2:]
    assert np.allclose(M @ qdd + h, G, atol=1e-12)
