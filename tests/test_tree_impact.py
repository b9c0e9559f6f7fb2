"""The derived impact of a rigid-body tree (blocks of the extended mass matrix and the contact
Jacobian by recursion over the tree) against the sum over its bodies, and a walker whose feet take
turns as the base against the conservation of angular momentum about the impact point."""

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from amble import Joint, Model, ModelError, base_relabel, simulate, stance_feet_walker
from amble.backend.kernels import build
from amble.derivation.tree_impact import tree_impact_terms
from amble.modelling.dag import dag_subs

DATA = Path(__file__).parent / "data"

# a small 3D biped: per leg hip roll (x), hip pitch (y), knee (y), a foot fixed to the shin
_LEG = """
  <link name="{s}_hip"><inertial><origin xyz="0 {y2} -0.02"/><mass value="1.1"/>
    <inertia ixx="0.002" iyy="0.0015" izz="0.0018" ixy="0.0001" ixz="-0.0002" iyz="0.00005"/></inertial></link>
  <link name="{s}_thigh"><inertial><origin xyz="0.01 0 -0.17"/><mass value="5"/>
    <inertia ixx="0.07" iyy="0.068" izz="0.009" ixy="0.001" ixz="-0.002" iyz="0.0006"/></inertial></link>
  <link name="{s}_shin"><inertial><origin xyz="0 0.004 -0.18"/><mass value="2.5"/>
    <inertia ixx="0.035" iyy="0.034" izz="0.003" ixy="0.0003" ixz="-0.0002" iyz="0.0001"/></inertial></link>
  <link name="{s}_foot"><inertial><origin xyz="0.03 0 -0.02"/><mass value="0.8"/>
    <inertia ixx="0.0008" iyy="0.003" izz="0.0035" ixy="0.0001" ixz="-0.00007" iyz="0.00004"/></inertial></link>
  <joint name="{s}_hip_roll" type="revolute"><parent link="torso"/><child link="{s}_hip"/>
    <origin xyz="0 {y} -0.08" rpy="{r} 0 0"/><axis xyz="1 0 0"/>{lim}</joint>
  <joint name="{s}_hip_pitch" type="revolute"><parent link="{s}_hip"/><child link="{s}_thigh"/>
    <origin xyz="0 0 -0.05"/><axis xyz="0 1 0"/>{lim}</joint>
  <joint name="{s}_knee" type="revolute"><parent link="{s}_thigh"/><child link="{s}_shin"/>
    <origin xyz="0.004 0 -0.38" rpy="0 0.04 0"/><axis xyz="0 1 0"/>{lim}</joint>
  <joint name="{s}_ankle" type="fixed"><parent link="{s}_shin"/><child link="{s}_foot"/>
    <origin xyz="0 0 -0.38"/></joint>"""
_LIM = '<limit lower="-2" upper="2" effort="1" velocity="1"/>'
BIPED = ('<?xml version="1.0"?>\n<robot name="biped6">\n  <link name="torso"><inertial><origin xyz="0.01 0 0.18"/>'
         '<mass value="12"/><inertia ixx="0.3" iyy="0.26" izz="0.12" ixy="0.01" ixz="-0.006" iyz="0.003"/>'
         '</inertial></link>' + _LEG.format(s="left", y=0.09, y2=0.01, r=0.02, lim=_LIM)
         + _LEG.format(s="right", y=-0.09, y2=-0.01, r=-0.02, lim=_LIM) + "\n</robot>\n")
SOLES = {"left_sole": ("left_foot", (0.0, 0.0, -0.04)), "right_sole": ("right_foot", (0.0, 0.0, -0.04))}


@pytest.fixture(scope="module")
def urdf(tmp_path_factory):
    path = tmp_path_factory.mktemp("urdf") / "biped6.urdf"
    path.write_text(BIPED)
    return path


def _stance(path, side):
    return Model.from_urdf(path, name=f"{side}_stance", base=f"{side}_foot", base_joint=Joint("spherical"),
                           base_coordinate="stance", pivot=f"{side}_sole", contact_points=SOLES)


def _num(expr, at):
    return np.array([[float(e) for e in row] for row in sp.Matrix(dag_subs(sp.Matrix(expr), at)).tolist()])


@pytest.mark.parametrize("robot", ["biped6", "rabbit"])
def test_tree_impact_blocks_equal_the_sum_over_bodies(robot, urdf):
    """Sᵀ = Σ mᵢ ∂rᵢ/∂q over the bodies' centres of mass, mₜ = Σ mᵢ and the contact Jacobian
    ∂p/∂q (positions differentiated), at random poses, against the tree recursion's blocks."""
    if robot == "rabbit":
        m = Model.from_urdf(DATA / "rabbit.urdf", base="left_foot", base_joint=Joint("revolute", axis=(0, 1, 0)),
                            base_coordinate="stance")
        point = "right_foot"
    else:
        m = _stance(urdf, "left")
        point = "right_sole"
    ST, mt, Jc = (m.tree.defs.expand(x) for x in tree_impact_terms(m.tree, point))
    masses = {k: v for k, v in m.masses.items() if k in m.tree.com_points}
    rng = np.random.default_rng(3)
    for _ in range(2):
        at = {q: sp.Float(v) for q, v in zip(m.q, rng.uniform(-1.2, 1.2, len(m.q)))}
        body_sum = sum(float(mi) * _num(m.jacobian(m.points[k]), at) for k, mi in masses.items())
        assert np.abs(_num(ST, at) - body_sum).max() <= 1e-12 * np.abs(body_sum).max()
        assert float(mt) == pytest.approx(sum(float(v) for v in masses.values()), rel=1e-14)
        J = _num(m.jacobian(m.points[point]), at)
        assert np.abs(_num(Jc, at) - J).max() <= 1e-12 * np.abs(J).max()


def _euler_rate_map(yaw, pitch):
    """ω (world) = E (ẏaw, ṗitch, ṙoll) of R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cy, sy, cp, sp_ = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    return np.array([[0.0, -sy, cy * cp], [0.0, cy, sy * cp], [1.0, 0.0, -sp_]])


def _angular_momentum_about_pivot(k, mode, x, names):
    """H (world, about the stance pivot at the origin) = E⁻ᵀ ∂K/∂(Euler rates): a rigid turn of
    the whole robot about the pivot changes only the base's Euler rates."""
    M, _, _ = k.dynamics(mode, 0.0, x, np.zeros(0))
    n = len(names)
    base = [names.index(f"stance_{a}") for a in ("yaw", "pitch", "roll")]
    p = (M @ x[n:])[base]
    E = _euler_rate_map(x[base[0]], x[base[1]])
    return np.linalg.solve(E.T, p)


def test_stance_feet_walker_conserves_angular_momentum_about_the_impact_point(urdf):
    modes = {"left": _stance(urdf, "left"), "right": _stance(urdf, "right")}
    w = stance_feet_walker("biped6-walk", modes, feet={"left": "left_sole", "right": "right_sole"}, hip="torso")
    names = [str(q) for q in modes["left"].q]
    n = len(names)
    x0 = np.zeros(2 * n)
    for name, v in {"stance_pitch": 0.05, "stance_roll": -0.03, "right_hip_pitch": -0.45, "right_knee": 0.25,
                    "left_hip_pitch": 0.0}.items():
        x0[names.index(name)] = v
    x0[n + names.index("stance_pitch")] = 1.2   # falling forward
    x0[n + names.index("right_hip_pitch")] = -0.5
    traj = simulate(w, x0=x0, steps=1, t_end=2.0)
    (ev,) = [e for e in traj.events if e.name == "heel_strike_right"]
    k = build(w)
    pts = k.meta["points"]
    pos, vel = k.kinematics_rows(np.zeros(2), np.array([0, 1]), np.array([ev.x_pre, ev.x_post]), np.zeros(0))
    c = pos[0, pts.index("right_sole")]
    assert abs(c[2]) <= 1e-9 and vel[0, pts.index("right_sole"), 2] < 0  # the swing foot lands
    # the relabelled pose is the same pose, seen from the new stance foot
    assert np.abs(pos[1] - (pos[0] - c)).max() <= 1e-12
    assert np.abs(vel[1, pts.index("right_sole")]).max() <= 1e-15  # the new stance foot is at rest
    # angular momentum about the impact point: the ground's impulse acts there only
    masses = {name: float(v) for name, v in modes["left"].masses.items()}
    P = sum(mv * vel[0, pts.index(name)] for name, mv in masses.items())
    H_pre = _angular_momentum_about_pivot(k, "left", ev.x_pre, names) - np.cross(c, P)
    H_post = _angular_momentum_about_pivot(k, "right", ev.x_post, [str(q) for q in modes["right"].q])
    assert np.abs(H_post - H_pre).max() <= 1e-12 * np.abs(H_pre).max()
    e = k.energy_rows(np.zeros(2), np.array([0, 1]), np.array([ev.x_pre, ev.x_post]), np.zeros(0))
    assert e[1, 0] < e[0, 0]  # a plastic impact loses kinetic energy
    assert e[1, 1] == pytest.approx(e[0, 1] - sum(masses.values()) * 9.81 * c[2], rel=1e-12)  # same pose


def test_stance_feet_walker_needs_a_pivot_at_the_stance_foot(urdf):
    off = Model.from_urdf(urdf, name="off", base="left_foot", base_joint=Joint("spherical"),
                          base_coordinate="stance", contact_points=SOLES)
    right = _stance(urdf, "right")
    with pytest.raises(ModelError, match="pivot"):
        stance_feet_walker("w", {"left": off, "right": right}, feet={"left": "left_sole", "right": "right_sole"},
                           hip="torso")
    free = Model.from_urdf(urdf, name="free", base="left_foot", base_joint=Joint("floating"),
                           base_coordinate="stance", pivot="left_sole", contact_points=SOLES)
    with pytest.raises(ModelError, match="revolute or spherical"):
        base_relabel(right, free)  # a floating base has no pivot to turn about


def test_a_foot_frame_merged_into_the_shin_can_be_the_next_base():
    """RABBIT's feet are massless frames on fixed joints (merged into the tibias): rooted at either
    foot as two stance modes, its footfall equals the one-mode walker's that relabels the legs by
    hand (the new stance angle the old swing foot's absolute angle, written out)."""
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from two_mode_walkers import rabbit_two_modes

    from amble import walker

    two = rabbit_two_modes()
    one = Model.from_urdf(DATA / "rabbit.urdf", base="left_foot", base_joint=Joint("revolute", axis=(0, 1, 0)),
                          base_coordinate="stance")
    q = {str(s): s for s in one.q}
    swap = {q["left_knee"]: q["right_knee"], q["left_hip"]: q["right_hip"], q["right_hip"]: q["left_hip"],
            q["right_knee"]: q["left_knee"],
            q["stance"]: q["stance"] - q["left_knee"] - q["left_hip"] + q["right_hip"] + q["right_knee"]}
    step = walker(one, foot="right_foot", hip="torso", slope=0.0, relabel=swap)
    names = [str(s) for s in one.q]
    assert names == [str(s) for s in two.modes["left"].q]
    n = len(names)
    x0 = np.zeros(2 * n)
    x0[names.index("left_hip")], x0[names.index("right_hip")] = 0.3, -0.2
    x0[names.index("right_knee")] = 0.1
    x0[n + names.index("stance")] = -1.1
    a = simulate(step, x0=x0, steps=1, t_end=3.0).step_events[0]
    b = simulate(two, x0=x0, steps=1, t_end=3.0).step_events[0]
    # the right mode's coordinates are (stance, right_knee, right_hip, left_hip, left_knee): the
    # one-mode walker's after its swap
    assert [str(s) for s in two.modes["right"].q] == ["stance", "right_knee", "right_hip", "left_hip", "left_knee"]
    assert b.t == pytest.approx(a.t, rel=1e-12)
    assert np.abs(b.x_post - a.x_post).max() <= 1e-10 * np.abs(a.x_post).max()
