"""MJCF files against MuJoCo itself (an independent implementation, reading the same file).

amble's mass matrix ``M``, bias ``h`` (with the joints' springs) and generalised force ``Γ``
(their damping) are compared with MuJoCo's ``mj_fullM`` and ``qfrc_bias − qfrc_passive`` after
``mj_forward``, at random states, to 1e-10 relative; the accelerations too. Hinge and slide
coordinates are MuJoCo's ``qpos − qpos0``. A free or ball joint is a quaternion with the angular
velocity in the body frame in MuJoCo, Euler angles ``R = Rz(yaw) Ry(pitch) Rx(roll) R_file`` in
amble: MuJoCo's velocities are ``v = J(q) q̇`` with ``J`` written out here from the rotations alone,
so ``M = Jᵀ M_mj J`` and ``h = Jᵀ (h_mj + M_mj J̇ q̇)``, ``J̇ q̇`` by complex-step differentiation
(exact to rounding)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

from amble import HybridSystem, Model, simulate
from amble.backend.kernels import build
from amble.errors import ModelError

mujoco = pytest.importorskip("mujoco", reason="MuJoCo (pip install mujoco) is the reference; not installed")
from oracles.mujoco_dynamics import full_mass_matrix  # noqa: E402  (after the skip)

DATA = Path(__file__).parent / "data"
REL = 1e-10


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0 * c], [s, c, 0 * c], [0 * c, 0 * c, 1 + 0 * c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0 * c, s], [0 * c, 1 + 0 * c, 0 * c], [-s, 0 * c, c]])


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1 + 0 * c, 0 * c, 0 * c], [0 * c, c, -s], [0 * c, s, c]])


def _euler_rates_to_body(a: np.ndarray, R0: np.ndarray) -> np.ndarray:
    """``W`` with ``ω_body = W ȧ`` for ``R = Rz(a0) Ry(a1) Rx(a2) R0`` (works on complex ``a``)."""
    Rz, Ry, Rx = _rz(a[0]), _ry(a[1]), _rx(a[2])
    cols = np.stack([np.array([0, 0, 1.0]), Rz @ np.array([0, 1.0, 0]), Rz @ Ry @ np.array([1.0, 0, 0])], axis=1)
    R = Rz @ Ry @ Rx @ R0
    return R.T @ cols


def _mat(quat) -> np.ndarray:
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, np.asarray(quat, dtype=float))
    return out.reshape(3, 3)


def _quat(R: np.ndarray) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mat2Quat(out, np.ascontiguousarray(R.real, dtype=float).reshape(-1))
    return out


class _Map:
    """amble's coordinates ``q`` (names) ↔ MuJoCo's ``qpos``/``qvel`` of the same file."""

    def __init__(self, m, names: list[str]) -> None:
        self.m, self.names, self.blocks = m, names, []
        idx = {n: i for i, n in enumerate(names)}
        for j in range(m.njnt):
            jn = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
            kind, qa, da = int(m.jnt_type[j]), int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            if kind == 0:  # free: x, y, z, yaw, pitch, roll
                R0 = _mat(m.qpos0[qa + 3:qa + 7])
                ids = [idx[f"{jn}_{s}"] for s in ("x", "y", "z", "yaw", "pitch", "roll")]
                self.blocks.append(("free", ids, qa, da, R0))
            elif kind == 1:
                ids = [idx[f"{jn}_{s}"] for s in ("yaw", "pitch", "roll")]
                self.blocks.append(("ball", ids, qa, da, np.eye(3)))
            else:
                self.blocks.append(("one", [idx[jn]], qa, da, None))

    def qpos_qvel(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m = self.m
        qpos, qvel = m.qpos0.copy(), np.zeros(m.nv)
        J = self.jacobian(q)
        qvel[:] = (J @ v).real
        for kind, ids, qa, _, R0 in self.blocks:
            if kind == "one":
                qpos[qa] += q[ids[0]]
            elif kind == "free":
                qpos[qa:qa + 3] += q[ids[:3]]
                qpos[qa + 3:qa + 7] = _quat(_rz(q[ids[3]]) @ _ry(q[ids[4]]) @ _rx(q[ids[5]]) @ R0)
            else:
                qpos[qa:qa + 4] = _quat(_rz(q[ids[0]]) @ _ry(q[ids[1]]) @ _rx(q[ids[2]]))
        return qpos, qvel

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """``J = ∂qvel/∂q̇`` (MuJoCo's free joint: world linear velocity, body angular velocity)."""
        J = np.zeros((self.m.nv, len(q)), dtype=complex)
        for kind, ids, _, da, R0 in self.blocks:
            if kind == "one":
                J[da, ids[0]] = 1.0
            elif kind == "free":
                J[da:da + 3, ids[:3]] = np.eye(3)
                J[da + 3:da + 6, ids[3:]] = _euler_rates_to_body(q[ids[3:]], R0)
            else:
                J[da:da + 3, ids] = _euler_rates_to_body(q[ids], R0)
        return J

    def jdot_v(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``J̇ q̇``: the derivative of ``J(q) q̇`` along ``q̇``, by a complex step of 1e-30."""
        h = 1e-30
        return (self.jacobian(q + 1j * h * v) @ v).imag / h


def _compare(path: Path, states: int = 20, fixed_base: bool = False, seed: int = 5) -> dict[str, float]:
    model = Model.from_mjcf(path, fixed_base=fixed_base)
    k = build(HybridSystem(model.name, model))
    spec = mujoco.MjSpec.from_file(str(path))
    if fixed_base:  # the same file with the free joint removed: the body welded where it stands
        for j in [j for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_FREE]:
            spec.delete(j)
    m = spec.compile()
    # amble reads neither contacts, joint limits nor actuators: MuJoCo's accelerations without them
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_ACTUATION
    d = mujoco.MjData(m)
    names = [str(s) for s in model.q]
    mp = _Map(m, names)
    n = len(names)
    assert m.nv == n
    rng = np.random.default_rng(seed)
    worst = dict(M=0.0, h=0.0, qdd=0.0)
    rel = lambda a, b: float(np.abs(a - b).max() / np.abs(b).max())
    for _ in range(states):
        q, v = rng.uniform(-1.2, 1.2, n), rng.uniform(-2.0, 2.0, n)
        d.qpos[:], d.qvel[:] = mp.qpos_qvel(q, v)
        mujoco.mj_forward(m, d)
        Mm = full_mass_matrix(m, d)
        J, Jdv = mp.jacobian(q).real, mp.jdot_v(q, v)
        x = np.concatenate([q, v])
        M, h, G = k.dynamics(0, 0.0, x, np.zeros(1))
        qdd = k.rhs(0, 0.0, x, np.zeros(1))[n:]
        hm = d.qfrc_bias - d.qfrc_passive
        worst["M"] = max(worst["M"], rel(M, J.T @ Mm @ J))
        worst["h"] = max(worst["h"], rel(h - G, J.T @ (hm + Mm @ Jdv)))
        worst["qdd"] = max(worst["qdd"], rel(J @ qdd + Jdv, d.qacc))
    return worst


def test_a_chain_with_offsets_springs_dampers_and_armature_matches_mujoco():
    """Hinges and a slide (two joints in one body), rotated frames and principal inertias, a
    tilted gravity, damping, a spring with its rest length, armature and a ``ref``."""
    worst = _compare(DATA / "mjcf_chain.xml", states=25)
    assert max(worst.values()) <= REL, worst


def test_a_floating_body_with_a_ball_joint_matches_mujoco_in_its_coordinates():
    worst = _compare(DATA / "mjcf_floater.xml", states=25)
    assert max(worst.values()) <= REL, worst


def test_a_welded_base_matches_mujoco_without_its_free_joint():
    worst = _compare(DATA / "mjcf_floater.xml", states=20, fixed_base=True)
    assert max(worst.values()) <= REL, worst


def _gymnasium_asset(name: str) -> Path:
    """A robot of Gymnasium's MuJoCo environments (a test dependency; located without importing it)."""
    import importlib.util

    spec = importlib.util.find_spec("gymnasium")
    if spec is None or spec.origin is None:
        pytest.skip("gymnasium (pip install gymnasium) ships the third-party robots; not installed")
    return Path(spec.origin).parent / "envs" / "mujoco" / "assets" / name


@pytest.mark.parametrize("name", ["ant.xml", "walker2d_v5.xml"])
def test_third_party_robots_match_mujoco(name):
    """Gymnasium's Ant (a quadruped on a free joint, armature and damping on its eight hinges) and
    Walker2d (planar: slides and hinges at the root), actuators and contacts left out on both sides."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # their actuators and contacts are not read
        worst = _compare(_gymnasium_asset(name), states=20)
    assert max(worst.values()) <= REL, worst


_TIED = """<mujoco model="tied"><worldbody>
  <body name="a" pos="0 0 1" euler="10 0 5"><joint name="j1" axis="0 1 0.2" damping="0.2" armature="0.01"/>
    <inertial pos="0.01 0 -0.2" quat="0.9 0.1 0.3 0" mass="1" diaginertia="0.02 0.015 0.006"/>
    <body name="b" pos="0.02 0 -0.4"><joint name="j2" axis="1 0 0.3" pos="0 0.01 0" damping="0.1"
        stiffness="2" armature="0.03"/>
      <inertial pos="0 0.02 -0.1" mass="0.6" diaginertia="0.01 0.008 0.003"/>
      <body name="c" pos="0 0 -0.3"><joint name="j3" type="slide" axis="0 0.2 1"/>
        <inertial pos="0 0 -0.05" mass="0.3" diaginertia="0.002 0.002 0.001"/></body></body></body>
</worldbody><equality><joint joint1="{one}" joint2="{two}" polycoef="0.1 {c1} 0 0 0"/></equality></mujoco>"""


@pytest.mark.parametrize("one, two, c1", [("j2", "j1", -0.7), ("j1", "j2", 1.6)])
def test_a_linear_joint_coupling_is_a_mimic_joint_checked_against_mujoco_projected(tmp_path, one, two, c1):
    """``θ₁ = 0.1 + c1 θ₂``: one coordinate fewer. MuJoCo holds the coupling by a constraint force,
    so the truth is its unconstrained M and bias (springs, dampers, armature of both joints)
    projected on the coupling, ``Gᵀ M G`` and ``Gᵀ (h − passive)`` with ``G = ∂θ/∂a``."""
    path = tmp_path / "tied.xml"
    path.write_text(_TIED.format(one=one, two=two, c1=c1))
    model = Model.from_mjcf(path)
    names = [str(s) for s in model.q]
    k = build(HybridSystem(model.name, model))
    m = mujoco.MjModel.from_xml_path(str(path))
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    d = mujoco.MjData(m)
    follower = "j2"  # the one read later follows: j2 = 0.1 + c1 j1, or j2 = (j1 − 0.1) / c1
    kk, cc = (c1, 0.1) if one == "j2" else (1 / c1, -0.1 / c1)
    assert names == ["j1", "j3"]
    G = np.array([[1.0, 0.0], [kk, 0.0], [0.0, 1.0]])
    rng = np.random.default_rng(4)
    for _ in range(20):
        a, v = rng.uniform(-1, 1, 2), rng.uniform(-2, 2, 2)
        d.qpos[:] = G @ a + np.array([0.0, cc, 0.0])
        d.qvel[:] = G @ v
        mujoco.mj_forward(m, d)
        Mm = full_mass_matrix(m, d)
        M, h, Gam = k.dynamics(0, 0.0, np.concatenate([a, v]), np.zeros(1))
        rel = lambda x, y: float(np.abs(x - y).max() / np.abs(y).max())
        assert rel(M, G.T @ Mm @ G) <= REL
        assert rel(h - Gam, G.T @ (d.qfrc_bias - d.qfrc_passive)) <= REL
    assert follower not in names


def test_the_coordinates_and_limits_of_a_file():
    model = Model.from_mjcf(DATA / "mjcf_floater.xml")
    assert [str(s) for s in model.q] == ["root_x", "root_y", "root_z", "root_yaw", "root_pitch", "root_roll",
                                         "shoulder_yaw", "shoulder_pitch", "shoulder_roll", "elbow", "hip"]
    chain = Model.from_mjcf(DATA / "mjcf_chain.xml")
    assert chain.tree.limits["j1"] == (None, None)


def _write(tmp_path, body: str, name: str = "m.xml") -> Path:
    p = tmp_path / name
    p.write_text(f"<mujoco><worldbody>{body}</worldbody></mujoco>")
    return p


def test_limits_are_read_relative_to_the_reference(tmp_path):
    p = _write(tmp_path, '<body><joint name="a" range="-30 60" ref="10" limited="true"/>'
                         '<geom size="0.1" mass="1"/></body>')
    model = Model.from_mjcf(p)
    lo, hi = model.tree.limits["a"]
    assert lo == pytest.approx(np.radians(-40), abs=1e-15) and hi == pytest.approx(np.radians(50), abs=1e-15)


@pytest.mark.parametrize("body, extra, what", [
    ('<body name="a"><joint name="j"/><geom size="0.1"/></body>'
     '<body name="b"><joint name="k"/><geom size="0.1"/></body>',
     '<equality><joint name="tie" joint1="j" joint2="k" polycoef="0 1 0.5 0 0"/></equality>',
     "equality constraint <joint> 'tie'"),
    ('<body name="a"><joint name="j"/><geom size="0.1"/>'
     '<body name="b" pos="0 0 -1"><joint name="k"/><geom size="0.1"/></body></body>',
     '<equality><connect name="loop" body1="b" body2="world" anchor="0 0 -1"/></equality>',
     "equality constraint <connect> 'loop'"),
    ('<body name="a" gravcomp="1"><joint name="j"/><geom size="0.1"/></body>', "", "gravcomp"),
    ('<body name="a"><joint type="free" name="f" damping="1"/><geom size="0.1"/></body>', "",
     "joint 'f' has damping"),
    ('<body name="a"><joint name="j" type="hinge"/><geom size="0.1"/></body><body name="a"/>', "",
     "MuJoCo cannot compile it"),
])
def test_what_is_not_read_is_refused_in_one_line(tmp_path, body, extra, what):
    p = tmp_path / "bad.xml"
    p.write_text(f"<mujoco>{extra}<worldbody>{body}</worldbody></mujoco>")
    with pytest.raises(ModelError) as e:
        Model.from_mjcf(p)
    assert what in str(e.value) and "\n" not in str(e.value)


def test_frictionloss_and_actuators_are_ignored_with_a_warning(tmp_path):
    p = tmp_path / "w.xml"
    p.write_text('<mujoco><worldbody><body><joint name="j" frictionloss="0.3"/><geom size="0.1"/></body>'
                 '</worldbody><actuator><motor joint="j"/></actuator></mujoco>')
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        Model.from_mjcf(p)
    text = " ".join(str(x.message) for x in w)
    assert "frictionloss" in text and "actuators" in text


def test_a_damped_joint_loses_energy_at_the_rate_d_qdot_squared():
    """dE/dt = −Σ d q̇² along a run (E includes the spring and the armature's kinetic energy)."""
    model = Model.from_mjcf(DATA / "mjcf_chain.xml")
    system = HybridSystem(model.name, model)
    x0 = np.array([0.3, -0.05, 0.4, 0.2, 1.0, 0.5, -1.0, 2.0])
    tr = simulate(system, x0, t_end=0.5, sample_dt=0.001, rtol=1e-12, atol=1e-12)
    assert tr.status == "end_time"
    e = tr.energy().sum(axis=1)
    power = -0.7 * tr.column("j1_dot") ** 2
    lost = cumulative_simpson(power, x=tr.t, initial=0.0)
    assert e[0] - e[-1] > 0.05  # it did lose energy
    assert np.max(np.abs((e - e[0]) - lost)) < 1e-8 * abs(e[0] - e[-1])
