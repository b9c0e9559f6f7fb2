"""Rigid-body trees from URDF files against Pinocchio (an independent implementation): the mass
matrix (CRBA), the bias h = C q̇ + g (RNEA at q̈ = 0) and the accelerations (ABA), with gravity and
the URDF's root link as the fixed base, at 100 random states."""

from pathlib import Path

import numpy as np
import pytest

from amble import HybridSystem, Model
from amble.backend.kernels import build

pin = pytest.importorskip("pinocchio", reason="Pinocchio (pip install pin) is the reference; not installed")

DATA = Path(__file__).parent / "data"


def _compare(name: str, states: int = 100) -> None:
    path = DATA / f"{name}.urdf"
    model = Model.from_urdf(path)
    k = build(HybridSystem(model.name, model))
    pm = pin.buildModelFromUrdf(str(path))
    assert pm.nq == pm.nv == len(model.q)  # revolute joints only: one coordinate each
    pd = pm.createData()
    idx = [pm.joints[pm.getJointId(str(s))].idx_q for s in model.q]
    assert sorted(idx) == list(range(pm.nq))
    rng = np.random.default_rng(13)
    p = np.zeros(1)
    for _ in range(states):
        q, v = rng.uniform(-1.5, 1.5, pm.nq), rng.uniform(-2.0, 2.0, pm.nq)
        qp, vp = np.zeros(pm.nq), np.zeros(pm.nv)
        qp[idx], vp[idx] = q, v
        x = np.concatenate([q, v])
        M, h, G = k.dynamics(0, 0.0, x, p)
        qdd = k.rhs(0, 0.0, x, p)[pm.nq:]
        Mp = pin.crba(pm, pd, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T  # Pinocchio fills the upper triangle
        hp = pin.rnea(pm, pd, qp, vp, np.zeros(pm.nv))
        nle = pin.nonLinearEffects(pm, pd, qp, vp)
        ap = pin.aba(pm, pd, qp, vp, np.zeros(pm.nv))
        assert np.array_equal(G, np.zeros(pm.nq))
        rel = lambda a, b: np.abs(a - b).max() / np.abs(b).max()
        assert rel(M, Mp[np.ix_(idx, idx)]) <= 1e-12
        assert rel(h, hp[idx]) <= 1e-12
        assert rel(h, nle[idx]) <= 1e-12
        assert rel(qdd, ap[idx]) <= 1e-12


@pytest.mark.parametrize("name", ["rabbit", "biped12"])
def test_urdf_robot_matches_pinocchio(name):
    _compare(name)


@pytest.mark.slow
def test_humanoid30_matches_pinocchio():
    _compare("humanoid30")
