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


def _serial_chain_urdf(path: Path, links: int, seed: int = 3) -> None:
    """A serial chain of ``links`` bodies on revolute joints: joint axes in turn along x, y and z of
    frames turned by non-zero roll, pitch and yaw, centres of mass off the joint axes and full
    (non-diagonal) inertia tensors, ``R diag(a, b, c) Rᵀ`` with principal moments that satisfy the
    triangle inequality."""
    rng = np.random.default_rng(seed)
    fmt = lambda v: " ".join(repr(round(float(a), 6)) for a in v)  # noqa: E731
    parts = ['<?xml version="1.0"?>', '<robot name="chain">', '  <link name="base"/>']
    for i in range(links):
        R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        inertia = R @ np.diag(rng.uniform(0.01, 0.02, 3)) @ R.T
        (ixx, ixy, ixz), (_, iyy, iyz), (_, _, izz) = inertia.tolist()
        parts += [f'  <link name="link{i}"><inertial>',
                  f'    <origin xyz="{fmt(rng.uniform(-0.05, 0.05, 2).tolist() + [-0.15])}" rpy="0 0 0"/>',
                  f'    <mass value="{round(float(rng.uniform(0.5, 2.0)), 6)!r}"/>',
                  f'    <inertia ixx="{ixx!r}" iyy="{iyy!r}" izz="{izz!r}" ixy="{ixy!r}" ixz="{ixz!r}" iyz="{iyz!r}"/>',
                  '  </inertial></link>',
                  f'  <joint name="j{i}" type="revolute">',
                  f'    <parent link="{"base" if i == 0 else f"link{i - 1}"}"/><child link="link{i}"/>',
                  f'    <origin xyz="{fmt([0.02, -0.01, -0.3 if i else 0.0])}"'
                  f' rpy="{fmt(rng.uniform(-0.6, 0.6, 3))}"/>',
                  f'    <axis xyz="{fmt(np.eye(3)[i % 3])}"/>',
                  '    <limit lower="-3" upper="3" effort="100" velocity="10"/>',
                  '  </joint>']
    path.write_text("\n".join([*parts, "</robot>", ""]))


def test_serial_chain_of_eight_links_matches_pinocchio(tmp_path):
    """A chain as long as the legs and arms of the 30-link humanoid below are short: eight joints in
    series, each body's M, h and q̈ through every joint before it."""
    path = tmp_path / "chain.urdf"
    _serial_chain_urdf(path, 8)
    model = Model.from_urdf(path)
    assert len(model.q) == 8
    k = build(HybridSystem(model.name, model))
    _check(model, k, np.zeros(1), pin.buildModelFromUrdf(str(path)), 50)


@pytest.mark.slow
def test_humanoid30_matches_pinocchio():
    _compare("humanoid30")


def _euler(yaw: float, pitch: float, roll: float) -> tuple[np.ndarray, ...]:
    cz, sz, cy, sy, cx, sx = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    return Rz, Ry, Rx


def test_floating_base_matches_pinocchio():
    """A floating base (x, y, z, yaw, pitch, roll) under the RABBIT URDF: M, h and q̈ equal
    Pinocchio's with the same six joints as a composite root joint; M and h equal Pinocchio's
    free-flyer (quaternion, body-frame velocity) mapped by the velocity Jacobian of the Euler
    angles, ``M = Jᵀ M_ff J``, ``h = Jᵀ h_ff`` (at rest in orientation, where J̇ q̇ = 0)."""
    from amble.modelling.tree import Joint

    path = DATA / "rabbit.urdf"
    model = Model.from_urdf(path, base_joint=Joint("floating"), base_coordinate="base")
    names = [str(s) for s in model.q]
    assert names[:6] == ["base_x", "base_y", "base_z", "base_yaw", "base_pitch", "base_roll"]
    k = build(HybridSystem(model.name, model))
    comp = pin.JointModelComposite()
    for j in (pin.JointModelPX(), pin.JointModelPY(), pin.JointModelPZ(),
              pin.JointModelRZ(), pin.JointModelRY(), pin.JointModelRX()):
        comp.addJoint(j)
    pm = pin.buildModelFromUrdf(str(path), comp)
    idx = []
    for s in names:
        if s.startswith("base_"):
            idx.append(names.index(s))
        else:
            idx.append(pm.joints[pm.getJointId(s)].idx_q)
    assert sorted(idx) == list(range(pm.nq))
    pd = pm.createData()
    ff = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    fd = ff.createData()
    rel = lambda a, b: np.abs(a - b).max() / np.abs(b).max()
    rng = np.random.default_rng(5)
    p = np.zeros(1)
    n = len(names)
    for _ in range(20):
        q, v = rng.uniform(-1.2, 1.2, n), rng.uniform(-2.0, 2.0, n)
        x = np.concatenate([q, v])
        M, h, _ = k.dynamics(0, 0.0, x, p)
        qdd = k.rhs(0, 0.0, x, p)[n:]
        qp, vp = np.zeros(n), np.zeros(n)
        qp[idx], vp[idx] = q, v
        Mp = pin.crba(pm, pd, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        assert rel(M, Mp[np.ix_(idx, idx)]) <= 1e-12
        assert rel(h, pin.rnea(pm, pd, qp, vp, np.zeros(n))[idx]) <= 1e-12
        assert rel(qdd, pin.aba(pm, pd, qp, vp, np.zeros(n))[idx]) <= 1e-12
        # free flyer: q = (p, quaternion), v = (Rᵀ ṗ, ω in the base frame)
        v[3:6] = 0.0  # base orientation at rest: J̇ q̇ = 0
        x = np.concatenate([q, v])
        M, h, _ = k.dynamics(0, 0.0, x, p)
        Rz, Ry, Rx = _euler(*q[3:6])
        R = Rz @ Ry @ Rx
        J = np.eye(n)
        J[0:3, 0:3] = R.T
        J[3:6, 3] = R.T @ [0, 0, 1]
        J[3:6, 4] = Rx.T @ [0, 1, 0]
        J[3:6, 5] = [1, 0, 0]
        jq = [ff.joints[ff.getJointId(s)].idx_q for s in names[6:]]
        jv = [ff.joints[ff.getJointId(s)].idx_v for s in names[6:]]
        qf = np.zeros(ff.nq)
        qf[0:3], qf[3:7] = q[0:3], pin.Quaternion(R).coeffs()
        qf[jq] = q[6:]
        vf = np.zeros(ff.nv)
        order = [0, 1, 2, 3, 4, 5, *jv]  # free-flyer velocity, then the joints in amble's order
        vf[order] = J @ v
        Mf = pin.crba(ff, fd, qf)
        Mf = (np.triu(Mf) + np.triu(Mf, 1).T)[np.ix_(order, order)]
        hf = pin.rnea(ff, fd, qf, vf, np.zeros(ff.nv))[order]
        assert rel(M, J.T @ Mf @ J) <= 1e-12
        assert rel(h, J.T @ hf) <= 1e-12


def test_constrained_tree_matches_pinocchio(tmp_path):
    """``constrained()`` of a tree model: the RABBIT with the left knee locked straight and the
    right knee driven by the left hip, ``right_knee = 0.5 sin(left_hip)``. Truth: Pinocchio on the
    URDF with the left knee made a fixed joint, projected on the remaining coordinates,
    ``M = Jᵀ M_p J`` and ``h = Jᵀ (h_p + M_p J̇ q̇)``."""
    import sympy as sp

    path = DATA / "rabbit.urdf"
    full = Model.from_urdf(path)
    a = full.symbol("left_hip")
    model = full.constrained("rabbit-locked", {full.symbol("left_knee"): 0,
                                               full.symbol("right_knee"): sp.sin(a) / 2})
    assert [str(s) for s in model.q] == ["left_hip", "right_hip"]
    k = build(HybridSystem(model.name, model))
    root = ET.parse(path).getroot()
    root.find("joint[@name='left_knee']").set("type", "fixed")
    edited = tmp_path / "locked.urdf"
    ET.ElementTree(root).write(edited)
    pm = pin.buildModelFromUrdf(str(edited))
    pd = pm.createData()
    iq = {s: pm.joints[pm.getJointId(s)].idx_q for s in ("left_hip", "right_hip", "right_knee")}
    rel = lambda x, y: np.abs(x - y).max() / np.abs(y).max()
    rng = np.random.default_rng(3)
    for _ in range(30):
        (th, ps), (thd, psd) = rng.uniform(-1.5, 1.5, 2), rng.uniform(-2.0, 2.0, 2)
        J = np.zeros((pm.nv, 2))
        J[iq["left_hip"], 0], J[iq["right_hip"], 1], J[iq["right_knee"], 0] = 1.0, 1.0, np.cos(th) / 2
        qp = np.zeros(pm.nq)
        qp[iq["left_hip"]], qp[iq["right_hip"]], qp[iq["right_knee"]] = th, ps, np.sin(th) / 2
        vp = J @ [thd, psd]
        jdqd = np.zeros(pm.nv)
        jdqd[iq["right_knee"]] = -np.sin(th) / 2 * thd**2
        Mp = pin.crba(pm, pd, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        hp = pin.rnea(pm, pd, qp, vp, np.zeros(pm.nv))
        x = np.array([th, ps, thd, psd])
        M, h, _ = k.dynamics(0, 0.0, x, np.zeros(1))
        assert rel(M, J.T @ Mp @ J) <= 1e-12
        assert rel(h, J.T @ (hp + Mp @ jdqd)) <= 1e-12
        qdd = k.rhs(0, 0.0, x, np.zeros(1))[2:]
        assert rel(qdd, np.linalg.solve(J.T @ Mp @ J, -J.T @ (hp + Mp @ jdqd))) <= 1e-11


def test_spherical_joint_matches_pinocchio():
    """A body on a spherical joint (yaw, pitch, roll) below a fixed offset, under gravity: M, h
    and q̈ equal Pinocchio's for the same rotations as a composite joint (RZ, RY, RX)."""
    from amble.modelling.tree import Joint

    mass, com = 2.5, (0.05, -0.02, -0.4)
    inertia = np.array([[0.03, 0.002, -0.001], [0.002, 0.05, 0.004], [-0.001, 0.004, 0.02]])
    model = Model("ball", dims=3)
    model.gravity(9.81)
    model.rigid_tree().body("bob", joint=Joint("spherical", xyz=(0.1, 0.0, 1.0)), mass=mass, com=com,
                            inertia=inertia, coordinate="ball")
    assert [str(s) for s in model.q] == ["ball_yaw", "ball_pitch", "ball_roll"]
    k = build(HybridSystem(model.name, model))
    pm = pin.Model()
    comp = pin.JointModelComposite()
    for j in (pin.JointModelRZ(), pin.JointModelRY(), pin.JointModelRX()):
        comp.addJoint(j)
    jid = pm.addJoint(0, comp, pin.SE3(np.eye(3), np.array([0.1, 0.0, 1.0])), "ball")
    pm.appendBodyToJoint(jid, pin.Inertia(mass, np.array(com), inertia), pin.SE3.Identity())
    pd = pm.createData()
    rel = lambda a, b: np.abs(a - b).max() / np.abs(b).max()
    rng = np.random.default_rng(11)
    for _ in range(20):
        q, v = rng.uniform(-1.2, 1.2, 3), rng.uniform(-2.0, 2.0, 3)
        x = np.concatenate([q, v])
        M, h, _ = k.dynamics(0, 0.0, x, np.zeros(1))
        Mp = pin.crba(pm, pd, q)
        assert rel(M, np.triu(Mp) + np.triu(Mp, 1).T) <= 1e-12
        assert rel(h, pin.rnea(pm, pd, q, v, np.zeros(3))) <= 1e-12
        assert rel(k.rhs(0, 0.0, x, np.zeros(1))[3:], pin.aba(pm, pd, q, v, np.zeros(3))) <= 1e-12
