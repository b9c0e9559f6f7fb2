"""Rigid-body trees from URDF files against Pinocchio (an independent implementation): the mass
matrix (CRBA), the bias h = C q̇ + g (RNEA at q̈ = 0) and the accelerations (ABA), with gravity and
the URDF's root link as the fixed base, at 100 random states."""

import xml.etree.ElementTree as ET
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
    _check(model, k, np.zeros(1), pin.buildModelFromUrdf(str(path)), states)


def _check(model: Model, k, p: np.ndarray, pm, states: int, seed: int = 13) -> None:
    """amble's M, h and q̈ (parameters ``p``) against Pinocchio's model ``pm`` at random states."""
    assert pm.nq == pm.nv == len(model.q)  # revolute joints only: one coordinate each
    pd = pm.createData()
    idx = [pm.joints[pm.getJointId(str(s))].idx_q for s in model.q]
    assert sorted(idx) == list(range(pm.nq))
    rng = np.random.default_rng(seed)
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


def test_urdf_parameters_are_run_time_inputs(tmp_path):
    """With ``parameters=True`` a link's mass and a joint offset are parameters of one compiled
    library: changed at run time, M, h and q̈ equal Pinocchio's for a URDF edited the same way."""
    path = DATA / "biped12.urdf"
    model = Model.from_urdf(path, parameters=True)
    k = build(HybridSystem(model.name, model))
    names = k.meta["params"]
    p = np.array(k.meta["param_defaults"])
    _check(model, k, p, pin.buildModelFromUrdf(str(path)), 10)
    root = ET.parse(path).getroot()
    mass = root.find("link[@name='left_thigh']/inertial/mass")
    origin = root.find("joint[@name='left_knee']/origin")
    m_new = 1.7 * float(mass.get("value"))
    xyz = [float(v) for v in origin.get("xyz").split()]
    xyz[2] *= 1.25
    mass.set("value", repr(m_new))
    origin.set("xyz", " ".join(map(repr, xyz)))
    edited = tmp_path / "edited.urdf"
    ET.ElementTree(root).write(edited)
    p2 = p.copy()
    p2[names.index("m_left_thigh")] = m_new
    p2[names.index("z_left_knee")] = xyz[2]
    _check(model, k, p2, pin.buildModelFromUrdf(str(edited)), 10, seed=7)
    # a zero in the file stays a structural zero, not a parameter
    assert "y_left_knee" not in names and "m_torso" not in names


@pytest.mark.parametrize("name", ["rabbit", "biped12"])
def test_urdf_robot_matches_pinocchio(name):
    _compare(name)


@pytest.mark.slow
def test_humanoid30_matches_pinocchio():
    _compare("humanoid30")
