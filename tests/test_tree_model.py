"""Rigid bodies and joints as modelling objects, and URDF import: closed forms and bad files."""

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from amble import HybridSystem, Model, ModelError, derive
from amble.backend.kernels import build
from amble.modelling.tree import Joint

G = 9.81


def _numeric(eq, model, q, v):
    subs = {**dict(zip(model.q, q)), **dict(zip(model.qd, v))}
    M = np.array(eq.M.subs(subs).evalf(), dtype=float)
    h = np.array(eq.h.subs(subs).evalf(), dtype=float).ravel()
    return M, h


def test_compound_pendulum_closed_form():
    # a body hanging from a revolute joint about y: M = m c² + I_yy, h = m g c sin q
    m = Model("pendulum", dims=3)
    m.gravity(G)
    mass, c, Iyy = 2.0, 0.3, 0.05
    m.rigid_tree().body("arm", joint=Joint("revolute", axis=(0, 1, 0)), mass=mass, com=(0, 0, -c),
                        inertia=np.diag([0.04, Iyy, 0.01]))
    eq = derive(m)
    assert eq.compact is not None
    for q in (0.0, 0.4, -1.2):
        M, h = _numeric(eq, m, [q], [0.7])
        assert M[0, 0] == pytest.approx(mass * c**2 + Iyy, rel=1e-14)
        assert h[0] == pytest.approx(mass * G * c * np.sin(q), rel=1e-13, abs=1e-15)


def test_prismatic_on_revolute_closed_form():
    # a slider (mass m2, point-like) on a massless rotating arm about z at distance r = q2:
    # M = diag(m2 r², m2), h = (2 m2 r ṙ θ̇, −m2 r θ̇²); gravity along −z does no work
    m = Model("slider", dims=3)
    m.gravity(G)
    T = m.rigid_tree()
    T.body("arm", joint=Joint("revolute", axis=(0, 0, 1)), coordinate="theta")
    T.body("slider", parent="arm", joint=Joint("prismatic", axis=(1, 0, 0)), mass=1.5, coordinate="r")
    eq = derive(m)
    M, h = _numeric(eq, m, [0.3, 0.8], [1.1, -0.4])
    assert np.allclose(M, np.diag([1.5 * 0.8**2, 1.5]), rtol=1e-14, atol=1e-14)
    assert np.allclose(h, [2 * 1.5 * 0.8 * -0.4 * 1.1, -1.5 * 0.8 * 1.1**2], rtol=1e-13, atol=1e-14)


def test_tree_points_and_energy_are_those_of_the_bodies():
    m = Model("pendulum", dims=3)
    m.gravity(G)
    T = m.rigid_tree()
    T.body("arm", joint=Joint("revolute", axis=(0, 1, 0)), mass=2.0, com=(0, 0, -0.3),
           inertia=np.diag([0.04, 0.05, 0.01]))
    T.point("tip", "arm", (0, 0, -0.6))
    q, qd = m.q[0], m.qd[0]
    for a, w in ((0.3, 1.2), (-1.0, 0.4)):
        at = {q: a, qd: w}
        tip = [float(c.subs(at)) for c in m.points["tip"]]
        assert tip == pytest.approx([-0.6 * np.sin(a), 0.0, -0.6 * np.cos(a)], abs=1e-15)  # about +y
        assert float(m.K.subs(at)) == pytest.approx((2.0 * 0.09 + 0.05) * w**2 / 2, rel=1e-14)
        assert float(m.V.subs(at)) == pytest.approx(-2.0 * G * 0.3 * np.cos(a), rel=1e-14)
        vel = [float(c.subs(at)) for c in m.dt(m.points["tip"])]
        assert vel == pytest.approx([-0.6 * np.cos(a) * w, 0.0, 0.6 * np.sin(a) * w], abs=1e-14)


def test_point_mass_models_keep_their_route():
    m = Model("plain", dims=3)
    (a,) = m.coordinates("a")
    m.point("p", (sp.sin(a), 0, -sp.cos(a)), mass=1)
    m.gravity(G)
    assert m.tree is None and derive(m).compact is None


def test_reroot_at_a_leaf_closed_form(tmp_path):
    # the URDF root hangs from its child when the child is the base: a pendulum about the joint
    urdf = tmp_path / "two.urdf"
    urdf.write_text(_urdf(links=[("a", 3.0, (0.0, 0.0, 0.2)), ("b", 1.0, (0, 0, 0))],
                          joints=[("j", "revolute", "a", "b", (0, 0, -0.5), (0, 1, 0))]))
    m = Model.from_urdf(urdf, base="b")
    assert [str(s) for s in m.q] == ["j"]
    eq = derive(m)
    # a's centre of mass is 0.7 m above the joint in a's frame; Iyy of a = 0.01
    for q in (0.0, 0.5):
        M, h = _numeric(eq, m, [q], [0.0])
        assert M[0, 0] == pytest.approx(3.0 * 0.7**2 + 0.01, rel=1e-13)
        assert abs(h[0]) == pytest.approx(3.0 * G * 0.7 * abs(np.sin(q)), rel=1e-12, abs=1e-12)


def _urdf(links, joints, inertia="ixx='0.01' iyy='0.01' izz='0.01' ixy='0' ixz='0' iyz='0'", skip_inertial=()):
    out = ["<robot name='t'>"]
    for name, mass, com in links:
        if name in skip_inertial:
            out.append(f"<link name='{name}'/>")
            continue
        out.append(f"<link name='{name}'><inertial><origin xyz='{' '.join(map(str, com))}'/>"
                   f"<mass value='{mass}'/><inertia {inertia}/></inertial></link>")
    for name, kind, parent, child, xyz, axis in joints:
        out.append(f"<joint name='{name}' type='{kind}'><parent link='{parent}'/><child link='{child}'/>"
                   f"<origin xyz='{' '.join(map(str, xyz))}'/><axis xyz='{' '.join(map(str, axis))}'/>"
                   "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>")
    return "\n".join(out) + "</robot>"


CHAIN = dict(links=[("base", 1.0, (0, 0, 0)), ("l1", 1.0, (0, 0, -0.1)), ("l2", 1.0, (0, 0, -0.1))],
             joints=[("j1", "revolute", "base", "l1", (0, 0, 0), (0, 1, 0)),
                     ("j2", "revolute", "l1", "l2", (0, 0, -0.2), (1, 0, 0))])


@pytest.mark.parametrize("change, needle", [
    (dict(skip_inertial=("l2",)), "'l2'"),
    (dict(joints=CHAIN["joints"] + [("j3", "revolute", "l2", "l1", (0, 0, 0), (0, 1, 0))]), "'l1'"),
    (dict(joints=[CHAIN["joints"][0], ("j2", "gimbal", "l1", "l2", (0, 0, 0), (0, 1, 0))]), "'j2'"),
    (dict(joints=[CHAIN["joints"][0], ("j2", "floating", "l1", "l2", (0, 0, 0), (0, 1, 0))]), "'j2'"),
    (dict(links=CHAIN["links"][:2] + [("l2", -1.0, (0, 0, 0))]), "'l2'"),
    (dict(inertia="ixx='0.01' iyy='-0.01' izz='0.01' ixy='0' ixz='0' iyz='0'"), "'l1'"),  # the fixed base's is not used
])
def test_bad_urdf_names_the_culprit(tmp_path, change, needle):
    spec = {**CHAIN, **change}
    path = tmp_path / "bad.urdf"
    path.write_text(_urdf(**spec))
    with pytest.raises(ModelError, match=needle):
        Model.from_urdf(path)


def test_massless_links_need_consent(tmp_path):
    path = tmp_path / "m.urdf"
    path.write_text(_urdf(**CHAIN, skip_inertial=("l1",)))
    with pytest.raises(ModelError, match="l1"):
        Model.from_urdf(path)
    m = Model.from_urdf(path, allow_massless=True)
    assert [str(s) for s in m.q] == ["j1", "j2"]


def test_contact_points_and_limits(tmp_path):
    path = tmp_path / "c.urdf"
    path.write_text(_urdf(**CHAIN))
    m = Model.from_urdf(path, contact_points={"toe": ("l2", (0.1, 0, -0.2))})
    x = m.points["toe"].subs({m.q[0]: 0, m.q[1]: 0})
    assert [float(v) for v in x] == pytest.approx([0.1, 0.0, -0.4])
    assert m.tree.limits["j1"] == (-1.0, 1.0)
    with pytest.raises(ModelError, match="base"):
        Model.from_urdf(path, contact_points={"toe": ("base", (0, 0, 0))})


def test_tree_model_simulates_with_energy_conserved():
    from amble import simulate

    path = Path(__file__).parent / "data" / "rabbit.urdf"
    m = Model.from_urdf(path)
    sysm = HybridSystem(m.name, m)
    k = build(sysm)
    x0 = np.array([0.3, -0.2, 0.5, 0.1, 0.0, 0.0, 0.0, 0.0])
    traj = simulate(sysm, x0=x0, t_end=1.0, rtol=1e-12, atol=1e-12)
    e = k.energy_rows(np.zeros(2), np.zeros(2, dtype=np.int64), np.array([x0, traj.x[-1]]), np.zeros(1)).sum(axis=1)
    assert abs(traj.x[-1] - x0).max() > 0.1  # it swings
    assert abs(e[1] - e[0]) <= 1e-9 * abs(e[0])


def test_urdf_walker_steps_with_a_derived_impact():
    # RABBIT re-rooted at its left foot; the right foot strikes, legs swap (a derived plastic impact)
    from amble import simulate, walker

    # a point foot: the stance foot pivots about y on the ground (the coordinate "stance")
    m = Model.from_urdf(Path(__file__).parent / "data" / "rabbit.urdf", base="left_foot",
                        base_joint=Joint("revolute", axis=(0, 1, 0)), base_coordinate="stance")
    q = {str(s): s for s in m.q}
    swap = {q["left_knee"]: q["right_knee"], q["left_hip"]: q["right_hip"],
            q["right_hip"]: q["left_hip"], q["right_knee"]: q["left_knee"],
            # the new stance foot's absolute angle (reversed joints turn by −q)
            q["stance"]: q["stance"] - q["left_knee"] - q["left_hip"] + q["right_hip"] + q["right_knee"]}
    w = walker(m, foot="right_foot", hip="torso", slope=0.0, relabel=swap)
    names = [str(s) for s in m.q]
    n = len(names)
    x0 = np.zeros(2 * n)
    x0[names.index("left_hip")], x0[names.index("right_hip")] = 0.25, -0.25
    x0[n + names.index("stance")] = -1.0
    tr = simulate(w, x0=x0, steps=1, t_end=3.0)
    (ev,) = [e for e in tr.events if e.name == "heel_strike"]
    k = build(w)
    pos, vel = k.kinematics_rows(np.zeros(1), np.zeros(1, dtype=np.int64), ev.x_pre[None, :], np.zeros(1))
    foot = k.meta["points"].index("right_foot")
    assert abs(pos[0, foot, 2]) < 1e-9 and vel[0, foot, 2] < 0  # the swing foot lands
    x = ev.x_post
    assert [x[names.index(a)] for a in ("left_knee", "left_hip")] == pytest.approx(
        [ev.x_pre[names.index(a)] for a in ("right_knee", "right_hip")], abs=0)
    e = k.energy_rows(np.zeros(2), np.zeros(2, dtype=np.int64), np.array([ev.x_pre, ev.x_post]), np.zeros(1))
    assert e[1, 0] < e[0, 0]  # a plastic impact loses kinetic energy
    assert e[1, 1] == pytest.approx(e[0, 1], rel=1e-12)  # the relabelling keeps the pose


def test_point_mass_on_a_tree_point_adds_to_the_body():
    # a 1 kg point mass at the tip of a compound pendulum: M = m c² + I_yy + m_tip l², h = g (m c + m_tip l) sin q
    m = Model("pendulum_tip", dims=3)
    m.gravity(G)
    T = m.rigid_tree()
    T.body("arm", joint=Joint("revolute", axis=(0, 1, 0)), mass=2.0, com=(0, 0, -0.3),
           inertia=np.diag([0.04, 0.05, 0.01]))
    T.point("tip", "arm", (0, 0, -0.6))
    m.mass("tip", 1.0)
    eq = derive(m)
    M, h = _numeric(eq, m, [0.4], [0.7])
    assert M[0, 0] == pytest.approx(2.0 * 0.09 + 0.05 + 0.36, rel=1e-14)
    assert h[0] == pytest.approx(G * (0.6 + 0.6) * np.sin(0.4), rel=1e-13)
    assert float(eq.G[0].subs(m.q[0], 0.4)) == pytest.approx(h[0], rel=1e-13)


def test_structure_text_is_canonical_and_linear_in_shared_parts():
    from amble.modelling.dag import dag_srepr

    x, y = sp.symbols("x y")
    a = sp.Add(sp.sin(x), y, evaluate=False)
    deep = a
    for _ in range(40):  # 2⁴⁰ paths through the shared parts: sympy.srepr would not finish
        deep = sp.Mul(deep, sp.Add(deep, 1, evaluate=False), evaluate=False)
    assert len(dag_srepr([deep])) < 10_000
    assert dag_srepr([sp.sin(x) + y]) == dag_srepr([y + sp.sin(x)])
    assert dag_srepr([sp.sin(x) + y]) != dag_srepr([sp.cos(x) + y])
