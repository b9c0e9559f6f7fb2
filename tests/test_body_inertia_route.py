"""A 3D chain written the thesis' way (points, rotation matrices, ``body_inertia``) against
Pinocchio: the rotational inertia takes Kane's form in the derivation (no derivative of the
kinetic energy), and M and h must be the rigid-body dynamics of the same chain."""

import numpy as np
import pytest
import sympy as sp

from amble import Model, Rx, Ry
from amble.derivation.equations import derive

pin = pytest.importorskip("pinocchio")

N, L, MASS, G = 4, 0.3, 1.2, 9.81
INERTIA = (0.011, 0.013, 0.002)  # body axes, about the link's centre of mass (kg m²)


def thesis_chain() -> Model:
    """Joints alternate about x and y; link i hangs along its own −z, mass at its middle."""
    m = Model("chain", dims=3)
    q = m.coordinates(" ".join(f"q{i}" for i in range(N)))
    m.gravity(G)
    R, tip, prev = sp.eye(3), sp.zeros(3, 1), "base"
    m.point("base", (0, 0, 0))
    for i, qi in enumerate(q):
        R = R * (Rx(qi) if i % 2 == 0 else Ry(qi))
        m.point(f"c{i}", tip - L / 2 * R[:, 2], mass=MASS)
        tip = tip - L * R[:, 2]
        m.point(f"p{i}", tip, link=prev)
        prev = f"p{i}"
        m.body_inertia(R, sp.diag(*INERTIA))
    return m


def pinocchio_chain():
    model = pin.Model()
    parent = 0
    for i in range(N):
        place = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0 if i == 0 else -L]))
        joint = pin.JointModelRX() if i % 2 == 0 else pin.JointModelRY()
        parent = model.addJoint(parent, joint, place, f"j{i}")
        model.appendBodyToJoint(parent, pin.Inertia(MASS, np.array([0.0, 0.0, -L / 2]), np.diag(INERTIA)),
                                pin.SE3.Identity())
    model.gravity.linear = np.array([0.0, 0.0, -G])
    return model, model.createData()


def test_the_thesis_style_chain_is_the_rigid_body_dynamics_of_pinocchio():
    m = thesis_chain()
    eq = derive(m)
    assert not [e for e in m._k_terms if e not in [s[2] for s in m._spins]]  # every spin by Kane's form
    f = sp.lambdify([m.q, m.qd], [eq.M, eq.h], "numpy")
    model, data = pinocchio_chain()
    rng = np.random.default_rng(3)
    for _ in range(20):
        q, v = rng.uniform(-1.5, 1.5, N), rng.uniform(-2, 2, N)
        M, h = (np.array(a, float) for a in f(q, v))
        Mp = pin.crba(model, data, q)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        hp = pin.rnea(model, data, q, v, np.zeros(N))
        assert np.max(np.abs(M - Mp)) <= 1e-12 * np.max(np.abs(Mp))
        assert np.max(np.abs(h.ravel() - hp)) <= 1e-12 * max(1.0, np.max(np.abs(hp)))
