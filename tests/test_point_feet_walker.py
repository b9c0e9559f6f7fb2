"""A point-foot walker made from a robot file in one call (``amble.models.load_walker``): Bolt, the
Open Dynamic Robot Initiative's biped from example-robot-data, takes a step under a joint PD law
holding a posture. Its footfall is checked against the conservation of angular momentum about the
impact point (the ground's impulse acts there only), the striking foot at rest after it and the
pose unchanged by the relabelling; its virtual constraints against the robot's mirror symmetry."""

from importlib.metadata import PackageNotFoundError, distribution

import numpy as np
import pytest
import sympy as sp

from amble import ModelError, compiled, simulate
from amble.modelling.dag import dag_subs
from amble.models import VirtualOutputs, load_walker

# a small 3D biped (hip roll about x, hip pitch and knee about y per leg; the hip roll frames
# tilted ±0.02 rad), as in test_tree_impact
_LEG = """
  <link name="{s}_hip"><inertial><origin xyz="0 {y2} -0.02"/><mass value="1.1"/>
    <inertia ixx="0.002" iyy="0.0015" izz="0.0018"/></inertial></link>
  <link name="{s}_thigh"><inertial><origin xyz="0.01 0 -0.17"/><mass value="5"/>
    <inertia ixx="0.07" iyy="0.068" izz="0.009"/></inertial></link>
  <link name="{s}_shin"><inertial><origin xyz="0 0 -0.18"/><mass value="2.5"/>
    <inertia ixx="0.035" iyy="0.034" izz="0.003"/></inertial></link>
  <link name="{s}_foot"><inertial><origin xyz="0.03 0 -0.02"/><mass value="0.8"/>
    <inertia ixx="0.0008" iyy="0.003" izz="0.0035"/></inertial></link>
  <joint name="{s}_hip_roll" type="revolute"><parent link="torso"/><child link="{s}_hip"/>
    <origin xyz="0 {y} -0.08" rpy="{r} 0 0"/><axis xyz="1 0 0"/>{lim}</joint>
  <joint name="{s}_hip_pitch" type="revolute"><parent link="{s}_hip"/><child link="{s}_thigh"/>
    <origin xyz="0 0 -0.05"/><axis xyz="0 1 0"/>{lim}</joint>
  <joint name="{s}_knee" type="revolute"><parent link="{s}_thigh"/><child link="{s}_shin"/>
    <origin xyz="0.004 0 -0.38"/><axis xyz="0 1 0"/>{lim}</joint>
  <joint name="{s}_ankle" type="fixed"><parent link="{s}_shin"/><child link="{s}_foot"/>
    <origin xyz="0 0 -0.38"/></joint>"""
_LIM = '<limit lower="-2" upper="2" effort="1" velocity="1"/>'
BIPED = ('<?xml version="1.0"?>\n<robot name="biped6">\n  <link name="torso"><inertial><origin xyz="0.01 0 0.18"/>'
         '<mass value="12"/><inertia ixx="0.3" iyy="0.26" izz="0.12"/></inertial></link>'
         + _LEG.format(s="left", y=0.09, y2=0.01, r=0.02, lim=_LIM)
         + _LEG.format(s="right", y=-0.09, y2=-0.01, r=-0.02, lim=_LIM) + "\n</robot>\n")
SOLES = {"left": ("left_foot", (0.0, 0.0, -0.04)), "right": ("right_foot", (0.0, 0.0, -0.04))}


def _angular_momentum_about_pivot(k, mode, x, names, p):
    """H (world, about the stance pivot at the origin) = E⁻ᵀ ∂K/∂(Euler rates), with
    ω = E (ẏaw, ṗitch, ṙoll) for R = Rz(yaw) Ry(pitch) Rx(roll): a rigid turn of the whole robot
    about the pivot changes only the base's Euler rates."""
    M, _, _ = k.dynamics(mode, 0.0, x, p)
    n = len(names)
    base = [names.index(f"stance_{a}") for a in ("yaw", "pitch", "roll")]
    yaw, pitch = x[base[0]], x[base[1]]
    E = np.array([[0.0, -np.sin(yaw), np.cos(yaw) * np.cos(pitch)],
                  [0.0, np.cos(yaw), np.sin(yaw) * np.cos(pitch)], [1.0, 0.0, -np.sin(pitch)]])
    return np.linalg.solve(E.T, (M @ x[n:])[base])


def _bolt_urdf():
    try:
        erd = distribution("example-robot-data")
    except PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install example-robot-data)")
    return next(erd.locate_file(f) for f in erd.files if str(f).endswith("bolt.urdf"))


#: Bolt's feet: a ball of 16 mm radius (the foot mesh) centred on the FOOT frame at the shin's tip;
#: the point foot is the ball's lowest point when the shin is vertical
FEET = {"left": ("FL_FOOT", (0.0, 0.0, -0.016)), "right": ("FR_FOOT", (0.0, 0.0, -0.016))}
#: a posture: the right (swing) hip flexed forward, its knee bent; the stance leg straight (rad)
POSE = {"stance_pitch": 0.05, "FR_HFE": -0.5, "FR_KFE": 0.3}


@pytest.fixture(scope="module")
def bolt_step():
    w = load_walker(_bolt_urdf(), FEET, max_step_time=1.0)
    for m in w.modes.values():
        kp, kd = m.parameters(kp=6.0, kd=0.15)   # N m/rad, N m s/rad: a light robot (1.3 kg)
        laws = {f"u_{q}": -kp * (q - m.parameter(f"ref_{q}", 0.0)) - kd * qd
                for q, qd in zip(m.q, m.qd) if not str(q).startswith("stance")}
        m.control(laws)
    names = [str(s) for s in w.modes["left"].q]
    n = len(names)
    x0 = np.zeros(2 * n)
    for name, v in POSE.items():
        x0[names.index(name)] = v
    x0[n + names.index("stance_pitch")] = 1.0   # rad/s: falling forward over the stance foot
    refs = {f"ref_{s}": POSE.get(s, 0.0) for s in names if not s.startswith("stance")}
    traj = simulate(w, x0=x0, steps=1, t_end=1.0, params=refs)
    return w, compiled(w), traj


def test_bolt_walker_takes_a_step_to_a_footfall(bolt_step):
    w, k, traj = bolt_step
    assert [str(s) for s in w.modes["left"].q][:3] == ["stance_yaw", "stance_pitch", "stance_roll"]
    assert len(w.modes["left"].inputs) == 6   # every joint but the pivot is actuated
    assert [a.limit for a in w.modes["left"].actuators] == [1000.0] * 6   # the file's effort
    (ev,) = traj.step_events
    assert ev.name == "heel_strike_right" and 0.0 < ev.t < 1.0
    pts = k.meta["points"]
    p = np.array([traj.parameters[name] for name in k.meta["params"]])
    pos, vel = k.kinematics_rows(np.zeros(1), np.array([0]), ev.x_pre[None], p)
    sole = pts.index("right_sole")
    assert abs(pos[0, sole, 2]) <= 1e-9 and vel[0, sole, 2] < 0   # the swing foot lands
    assert pos[0, pts.index("base_link"), 2] > 0.3                # the hip is still up


def test_bolt_footfall_conserves_angular_momentum_about_the_impact_point(bolt_step):
    w, k, traj = bolt_step
    ev = traj.step_events[0]
    pts = k.meta["points"]
    p = np.array([traj.parameters[name] for name in k.meta["params"]])
    pos, vel = k.kinematics_rows(np.zeros(2), np.array([0, 1]), np.array([ev.x_pre, ev.x_post]), p)
    c = pos[0, pts.index("right_sole")]
    # the relabelled pose is the pre-impact pose seen from the new stance foot: every point moved by −c
    assert np.abs(pos[1] - (pos[0] - c)).max() <= 1e-12
    assert np.abs(vel[1, pts.index("right_sole")]).max() <= 1e-14   # the striking foot at rest
    assert vel[1, pts.index("left_sole"), 2] > 0                      # the old stance foot lifts off
    masses = {name: float(v) for name, v in w.modes["left"].masses.items()}
    P = sum(mv * vel[0, pts.index(name)] for name, mv in masses.items())
    left, right = ([str(q) for q in w.modes[m].q] for m in ("left", "right"))
    H_pre = _angular_momentum_about_pivot(k, "left", ev.x_pre, left, p) - np.cross(c, P)
    H_post = _angular_momentum_about_pivot(k, "right", ev.x_post, right, p)
    assert np.abs(H_post - H_pre).max() <= 1e-11 * np.abs(H_pre).max()


def _mirror(names_from, names_to, q, signs):
    """The pose ``q`` (coordinates ``names_from``) reflected across the sagittal plane, in the
    other mode's coordinates: each joint to its counterpart with ``signs``, yaw and roll negated."""
    out = np.zeros(len(names_to))
    for i, name in enumerate(names_from):
        if name.startswith("stance"):
            out[names_to.index(name)] = -q[i] if name != "stance_pitch" else q[i]
        else:
            other = name.replace("FL_", "FX_").replace("FR_", "FL_").replace("FX_", "FR_")
            out[names_to.index(other)] = signs[name[3:]] * q[i]
    return out


def test_bolt_virtual_outputs_of_a_mirrored_pose_are_the_same():
    """Bolt's roll joints (HAA, axis x on both legs) mirror with a change of sign, its pitch joints
    (HFE, KFE, axis y) without: the right-stance outputs and phase of the mirror image of a
    left-stance pose equal the left-stance ones, and the mirrored pose is the mirror image of the
    robot (its feet reflected across the sagittal plane) — the signs checked by the kinematics."""
    w = load_walker(_bolt_urdf(), FEET, virtual=VirtualOutputs(degree=3))
    L, R = w.modes["left"], w.modes["right"]
    names_l, names_r = [str(q) for q in L.q], [str(q) for q in R.q]
    assert [str(e) for e in R.virtual.outputs] == ["-FR_HAA", "FR_HFE", "FR_KFE", "-FL_HAA", "FL_HFE", "FL_KFE"]
    assert [str(e) for e in L.virtual.outputs] == ["FL_HAA", "FL_HFE", "FL_KFE", "FR_HAA", "FR_HFE", "FR_KFE"]
    assert all(not any(sp.diff(e, a, b) for a in L.q for b in L.q) for e in [L.virtual.phase])  # affine in q
    signs = {"HAA": -1.0, "HFE": 1.0, "KFE": 1.0}
    rng = np.random.default_rng(5)
    for _ in range(3):
        ql = rng.uniform(-0.6, 0.6, len(names_l))
        qr = _mirror(names_l, names_r, ql, signs)
        at_l = {s: sp.Float(v) for s, v in zip(L.q, ql)}
        at_r = {s: sp.Float(v) for s, v in zip(R.q, qr)}
        yl = [float(e.subs(at_l)) for e in [*L.virtual.outputs, L.virtual.phase]]
        yr = [float(e.subs(at_r)) for e in [*R.virtual.outputs, R.virtual.phase]]
        assert np.allclose(yl, yr, rtol=0, atol=1e-12)
        # the mirrored pose is the robot's mirror image: its soles exactly (the file's foot offsets
        # are mirror images), its shins' centres of mass to the file's rounding
        for a, b, tol in (("right_sole", "left_sole", 1e-12), ("left_sole", "right_sole", 1e-12),
                          ("FR_LOWER_LEG", "FL_LOWER_LEG", 1e-6)):
            pa = np.array([float(e) for e in dag_subs(L.points[a], at_l)])
            pb = np.array([float(e) for e in dag_subs(R.points[b], at_r)])
            assert np.abs(pb - pa * np.array([1.0, -1.0, 1.0])).max() <= tol


@pytest.fixture(scope="module")
def biped6(tmp_path_factory):
    path = tmp_path_factory.mktemp("walker") / "biped6.urdf"
    path.write_text(BIPED)
    return path


def test_load_walker_refuses_feet_it_cannot_stand_on(biped6, tmp_path):
    soles = SOLES
    with pytest.raises(ModelError, match="no link 'left_toe'"):
        load_walker(biped6, {"left": ("left_toe", (0, 0, 0)), "right": soles["right"]})
    with pytest.raises(ModelError, match="not a leaf"):
        load_walker(biped6, {"left": ("left_shin", (0, 0, 0)), "right": soles["right"]})
    with pytest.raises(ModelError, match="same link"):
        load_walker(biped6, {"left": soles["left"], "right": soles["left"]})
    with pytest.raises(ModelError, match="give two stance feet"):
        load_walker(biped6, {"left": soles["left"]})
    with pytest.raises(ModelError, match=r"\(link, \(x, y, z\)\)"):
        load_walker(biped6, {"left": "left_foot", "right": soles["right"]})
    with pytest.raises(ModelError, match="hip: .* no link 'pelvis'"):
        load_walker(biped6, soles, hip="pelvis")
    with pytest.raises(ModelError, match="pivot"):
        load_walker(biped6, soles, pivot="ball")
    with pytest.raises(ModelError, match="URDF"):
        load_walker(tmp_path / "robot.xml", soles)
    # legs that are not mirror images: the right knee turns about z
    skew = tmp_path / "skew.urdf"
    text = BIPED.split('<joint name="right_knee"')
    tail = text[1].replace('<axis xyz="0 1 0"/>', '<axis xyz="0 0 1"/>', 1)
    skew.write_text(text[0] + '<joint name="right_knee"' + tail)
    with pytest.raises(ModelError, match="not mirror images"):
        load_walker(skew, soles, virtual=VirtualOutputs())
    w = load_walker(skew, soles, virtual=VirtualOutputs(mirror=False))   # unsigned outputs
    assert [str(e) for e in w.modes["right"].virtual.outputs][:3] == ["right_hip_roll", "right_hip_pitch",
                                                                      "right_knee"]


def test_load_walker_on_a_small_biped_mirrors_its_roll_joints(biped6):
    """The 6-DOF biped's hip roll joints turn about x on both legs (frames tilted ±0.02 rad): their
    angles change sign in the mirror image, the pitch joints' do not; a revolute pivot gives one
    stance coordinate."""
    soles = SOLES
    w = load_walker(biped6, soles, virtual=VirtualOutputs(degree=2))
    assert [str(e) for e in w.modes["right"].virtual.outputs] == [
        "-right_hip_roll", "right_hip_pitch", "right_knee", "-left_hip_roll", "left_hip_pitch", "left_knee"]
    assert w.hip == "torso" and {str(k): float(v) for k, v in w.modes["left"].params.items()}["alpha_5_2"] == 0.0
    planar = load_walker(biped6, soles, pivot=(0, 1, 0))
    assert [str(q) for q in planar.modes["left"].q][0] == "stance"
    assert all(a.limit == 1.0 for a in planar.modes["left"].actuators)   # the file's effort


@pytest.mark.slow
def test_bolt_virtual_constraints_drive_the_outputs_as_their_closed_form():
    """With constant desired outputs (every Bézier coefficient of an output equal: a posture) the
    input–output linearising law makes each output ``y = h₀(q) − h_d`` obey
    ``ÿ = −kd ẏ/ε − kp y/ε²``; with ``kp = 1``, ``kd = 2`` and ``ẏ(0) = 0`` that is
    ``y(t) = y(0) (1 + t/ε) e^(−t/ε)`` — on Bolt's compiled right-stance mode, whose outputs carry
    the mirror signs."""
    posture = [0.1, 0.3, -0.6, -0.05, 0.3, -0.6]   # rad: stance leg, then swing leg (HAA, HFE, KFE)
    eps = 0.02
    w = load_walker(_bolt_urdf(), FEET, max_step_time=1.0,
                    virtual=VirtualOutputs(degree=3, alpha=[[v] * 4 for v in posture], epsilon=eps))
    R = w.modes["right"]
    names = [str(s) for s in R.q]
    n = len(names)
    start = {"FR_HAA": 0.05, "FR_HFE": 0.35, "FR_KFE": -0.5, "FL_HAA": -0.1, "FL_HFE": 0.2, "FL_KFE": -0.7}
    x0 = np.zeros(2 * n)
    for name, v in start.items():
        x0[names.index(name)] = v
    traj = simulate(w, mode="right", x0=x0, t_end=0.06, rtol=1e-11, atol=1e-11)
    assert not traj.step_events
    outputs = [(-1.0, "FR_HAA"), (1.0, "FR_HFE"), (1.0, "FR_KFE"), (-1.0, "FL_HAA"), (1.0, "FL_HFE"),
               (1.0, "FL_KFE")]
    tau = traj.t / eps
    for (s, name), target in zip(outputs, posture):
        y = s * traj.column(name) - target
        expected = (s * start[name] - target) * (1 + tau) * np.exp(-tau)
        assert np.abs(y - expected).max() <= 1e-9, name
