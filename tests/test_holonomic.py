"""Holonomic constraints inside a mode (``Model.holonomic``): a planar four-bar linkage written as
three free rods whose loop is closed by two constraint equations, against an independent
one-degree-of-freedom solution (tests/oracles/four_bar.py: closed-form kinematics, Lagrange's
equation in the crank angle, solve_ivp) and an independent KKT solve for the constraint forces."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from oracles import four_bar as fb

from amble import HybridSystem, Joint, Model, compiled, linearize, simulate
from amble.errors import ExpressionError, ModelError
from amble.simulation.engine import Options, run

TH1, W1 = 0.3, 2.0  # start: crank angle (rad) and rate (rad/s); the crank turns over once in 3 s


def four_bar(baumgarte: tuple[float, float] | None = None) -> HybridSystem:
    m = Model("four-bar")
    th1, th2, th3 = m.coordinates("theta1 theta2 theta3")
    a, b, c, d = m.parameters(a=fb.LINKS["a"], b=fb.LINKS["b"], c=fb.LINKS["c"], d=fb.LINKS["d"])
    m1, m2, m3, g = m.parameters(**fb.MASSES, g=fb.G)
    u = lambda x: sp.Matrix([sp.cos(x), sp.sin(x)])  # noqa: E731
    tip = m.point("B", a * u(th1))
    m.point("crank", a / 2 * u(th1), mass=m1)
    m.point("coupler", tip + b / 2 * u(th2), mass=m2)
    m.point("rocker", sp.Matrix([d, 0]) + c / 2 * u(th3), mass=m3)
    for angle, mass, length in ((th1, m1, a), (th2, m2, b), (th3, m3, c)):
        m.inertia(angle, mass * length**2 / 12)
    m.gravity(g)
    # the closure as text, read by the safe parser in the model's names
    m.holonomic("loop", ["a*cos(theta1) + b*cos(theta2) - d - c*cos(theta3)",
                         "a*sin(theta1) + b*sin(theta2) - c*sin(theta3)"], baumgarte=baumgarte)
    return HybridSystem("four-bar", m)


@pytest.fixture(scope="module")
def system() -> HybridSystem:
    return four_bar()


def _params(k) -> np.ndarray:
    return np.array(k.meta["param_defaults"], dtype=float)


def test_four_bar_follows_its_reduced_dynamics(system):
    x0 = fb.state(TH1, W1)
    traj = simulate(system, x0, t_end=3.0, rtol=1e-13, atol=1e-13, sample_dt=0.01)
    assert traj.status == "end_time"
    ref = fb.reduced_motion(TH1, W1, traj.t)
    assert np.ptp(traj.x[:, 0]) > 4.0  # the crank turns over: not a small swing
    assert np.max(np.abs(traj.x[:, 0] - ref[:, 0])) <= 1e-8
    assert np.max(np.abs(traj.x[:, 3] - ref[:, 1])) <= 1e-8
    # the closure does no work: K + V (amble's, and the oracle's of amble's states) is conserved
    E = traj.energy().sum(axis=1)
    assert np.ptp(E) / abs(E[0]) <= 1e-9
    E_ref = np.array([fb.energy(x) for x in traj.x])
    assert np.max(np.abs(E - E_ref)) <= 1e-9 * abs(E_ref[0])
    drift = np.max(np.abs([fb.closure(x) for x in traj.x]))  # |φ| without stabilisation
    assert drift <= 1e-10, drift
    lam = traj.constraint_forces()  # per recorded row, by name
    assert list(lam) == ["loop[0]", "loop[1]"]
    np.testing.assert_allclose(np.column_stack([lam["loop[0]"], lam["loop[1]"]])[::25],
                               [fb.kkt(x)[1] for x in traj.x[::25]], rtol=1e-10, atol=1e-10)


def test_a_rigid_body_tree_closes_its_loop_between_two_bodies():
    """The same linkage as a rigid-body tree (two branches from the base: crank then coupler, and
    the rocker; relative joint angles) closed by the coupler's end meeting the rocker's."""
    m = Model("four-bar-tree", dims=3)
    m.gravity(fb.G)
    T = m.rigid_tree()
    L, Ms = fb.LINKS, fb.MASSES
    ax = (0, -1, 0)  # about −y: a positive angle turns +x towards +z, as in the oracle

    def rod(mass: float, length: float) -> dict:
        return dict(mass=mass, com=(length / 2, 0, 0), inertia=np.diag([0.0, 1.0, 1.0]) * mass * length**2 / 12)

    T.body("crank", joint=Joint("revolute", axis=ax), coordinate="q1", **rod(Ms["m1"], L["a"]))
    T.body("coupler", parent="crank", joint=Joint("revolute", axis=ax, xyz=(L["a"], 0, 0)), coordinate="q2",
           **rod(Ms["m2"], L["b"]))
    T.body("rocker", joint=Joint("revolute", axis=ax, xyz=(L["d"], 0, 0)), coordinate="q3", **rod(Ms["m3"], L["c"]))
    c1, c2 = T.point("C", "coupler", (L["b"], 0, 0)), T.point("C'", "rocker", (L["c"], 0, 0))
    m.holonomic("loop", [c1[0] - c2[0], c1[2] - c2[2]])
    system = HybridSystem("four-bar-tree", m)
    th = fb.state(TH1, W1)
    relative = np.array([[1, 0, 0], [-1, 1, 0], [0, 0, 1]])  # (θ1, θ2, θ3) → (q1, q2 = θ2 − θ1, q3)
    x0 = np.concatenate([relative @ th[:3], relative @ th[3:]])
    traj = simulate(system, x0, t_end=3.0, rtol=1e-13, atol=1e-13, sample_dt=0.01)
    ref = fb.reduced_motion(TH1, W1, traj.t)
    assert np.max(np.abs(traj.x[:, 0] - ref[:, 0])) <= 1e-8
    absolute = np.linalg.inv(relative)
    full = np.column_stack([traj.x[:, :3] @ absolute.T, traj.x[:, 3:] @ absolute.T])
    k = compiled(system)
    lam = k.constraint_forces_many(0, traj.t, traj.x, _params(k))
    np.testing.assert_allclose(lam, [fb.kkt(x)[1] for x in full],
                               atol=1e-9)


def _four_bar_mjcf(th: tuple[float, float, float]) -> str:
    """The linkage as MJCF, posed closed at the angles ``th`` (the file's pose: coordinates zero)."""
    L, Ms = fb.LINKS, fb.MASSES

    def inertial(mass: float, length: float) -> str:
        moment = mass * length**2 / 12
        return f'<inertial pos="{length / 2!r} 0 0" mass="{mass!r}" diaginertia="1e-6 {moment!r} {moment!r}"/>'

    hinge = 'type="hinge" axis="0 -1 0"'
    return f"""<mujoco model="four-bar"><compiler angle="radian"/><option gravity="0 0 -{fb.G!r}"/><worldbody>
  <body name="crank" euler="0 {-th[0]!r} 0"><joint name="q1" {hinge}/>{inertial(Ms["m1"], L["a"])}
    <body name="coupler" pos="{L["a"]!r} 0 0" euler="0 {th[0] - th[1]!r} 0"><joint name="q2" {hinge}/>
      {inertial(Ms["m2"], L["b"])}</body></body>
  <body name="rocker" pos="{L["d"]!r} 0 0" euler="0 {-th[2]!r} 0"><joint name="q3" {hinge}/>
    {inertial(Ms["m3"], L["c"])}</body>
</worldbody><equality><connect name="loop" body1="coupler" body2="rocker" anchor="{L["b"]!r} 0 0"/></equality>
</mujoco>"""


def test_an_mjcf_connect_closes_the_loop_of_a_file(tmp_path):
    """``<equality><connect>`` of two bodies is read as a holonomic constraint (the component
    normal to the planar loop, which no joint moves, left out)."""
    pytest.importorskip("mujoco")
    th = fb.state(TH1, W1)
    path = tmp_path / "four_bar.xml"
    path.write_text(_four_bar_mjcf(tuple(float(v) for v in th[:3])))
    model = Model.from_mjcf(path)
    assert model.constraint_names == ["loop[0]", "loop[1]"]
    system = HybridSystem("four-bar-mjcf", model)
    x0 = np.array([0.0, 0.0, 0.0, th[3], th[4] - th[3], th[5]])  # coordinates from the file's pose
    traj = simulate(system, x0, t_end=3.0, rtol=1e-13, atol=1e-13, sample_dt=0.01)
    ref = fb.reduced_motion(TH1, W1, traj.t)
    assert np.max(np.abs(traj.x[:, 0] + TH1 - ref[:, 0])) <= 1e-8
    E = traj.energy().sum(axis=1)
    assert np.ptp(E) / abs(E[0]) <= 1e-9


def test_constraint_forces_match_an_independent_kkt_solve(system):
    k = compiled(system)
    assert k.constraint_names("four-bar") == ["loop[0]", "loop[1]"]
    p = _params(k)
    rng = np.random.default_rng(3)
    X = np.array([fb.state(th, w) for th, w in zip(rng.uniform(-np.pi, np.pi, 8), rng.uniform(-3, 3, 8))])
    lam = k.constraint_forces_many("four-bar", 0.0, X, p)
    for x, lx in zip(X, lam):
        qdd, lam_ref = fb.kkt(x)
        np.testing.assert_allclose(lx, lam_ref, rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(k.rhs("four-bar", 0.0, x, p)[3:], qdd, rtol=1e-11, atol=1e-11)
    np.testing.assert_array_equal(k.constraint_forces("four-bar", 0.0, X[0], p), lam[0])


def test_baumgarte_pulls_a_violated_start_back():
    x0 = fb.state(TH1, W1)
    x0[1] += 1e-3  # the loop open by about 1 mm
    free = simulate(four_bar(), x0, t_end=2.0, sample_dt=0.01)
    held = simulate(four_bar((10.0, 10.0)), x0, t_end=2.0, sample_dt=0.01)
    assert np.max(np.abs(fb.closure(free.x[-1]))) > 1e-4  # without feedback the error stays
    assert np.max(np.abs(fb.closure(held.x[-1]))) < 1e-8


def test_flow_jacobian_and_sensitivities_match_finite_differences(system):
    """The tangent of the constrained solve (rhs_jac) and the variational equations of a run."""
    k = compiled(system, derivatives=True)
    p = _params(k)
    x = fb.state(0.7, 1.3)
    x[4] += 0.2  # off the constraint's velocity manifold: the right-hand side is defined there too
    _, A, B = k.rhs_jacobian("four-bar", 0.0, x, p)
    h = 1e-6
    A_fd = np.column_stack([(k.rhs(0, 0.0, x + h * e, p) - k.rhs(0, 0.0, x - h * e, p)) / (2 * h) for e in np.eye(6)])
    B_fd = np.column_stack([(k.rhs(0, 0.0, x, p + h * e) - k.rhs(0, 0.0, x, p - h * e)) / (2 * h)
                            for e in np.eye(p.size)])
    np.testing.assert_allclose(A, A_fd, atol=1e-7 * np.abs(A).max())
    np.testing.assert_allclose(B, B_fd, atol=1e-7 * np.abs(B).max())
    opts = Options(rtol=1e-12, atol=1e-12)
    x0 = fb.state(TH1, W1)
    end = lambda x0_, p_: run(k, p_, 0, x0_, t_end=1.0, opts=opts).x  # noqa: E731
    sens = run(k, p, 0, x0, t_end=1.0, opts=opts, sensitivities=True).sensitivity
    S_fd = np.column_stack([(end(x0 + h * e, p) - end(x0 - h * e, p)) / (2 * h) for e in np.eye(6)])
    Sp_fd = np.column_stack([(end(x0, p + h * e) - end(x0, p - h * e)) / (2 * h) for e in np.eye(p.size)])
    np.testing.assert_allclose(sens.dx_dx0, S_fd, atol=1e-6)
    np.testing.assert_allclose(sens.dx_dp, Sp_fd, atol=1e-6)
    # the implicit integrator runs on the same exact Jacobian
    radau = run(k, p, 0, x0, t_end=1.0, opts=Options(rtol=1e-11, atol=1e-11, method="radau"))
    np.testing.assert_allclose(radau.x, end(x0, p), atol=1e-9)


def test_analyses_written_for_unconstrained_dynamics_refuse(system):
    with pytest.raises(ModelError, match="mode 'four-bar' has holonomic constraints"):
        linearize(system, fb.state(TH1, W1))


def test_declaration_errors():
    m = Model("bad")
    x, z = m.coordinates("x z", unit="m")
    m.point("p", (x, z), mass=1.0)
    with pytest.raises(ModelError, match="not on time"):
        m.holonomic("moving", [x - sp.Symbol("t", real=True)])
    with pytest.raises(ModelError, match="neither a coordinate nor a parameter"):
        m.holonomic("unknown", [x - sp.Symbol("w")])
    with pytest.raises(ExpressionError):
        m.holonomic("text", ["__import__('os')"])
    with pytest.raises(ModelError, match="baumgarte"):
        m.holonomic("gains", [x], baumgarte=(1.0, -1.0))
    m.holonomic("floor", "z")
    with pytest.raises(ModelError, match="already declared"):
        m.holonomic("floor", [z])
    assert m.constraint_names == ["floor"]


def test_a_held_point_mass_pushes_on_its_support():
    """A point mass held at height 0 by one constraint: λ is the support's force, m g, upward."""
    m = Model("held")
    x, z = m.coordinates("x z", unit="m")
    mass, g = m.parameters(mass=2.0, g=9.81)
    m.point("p", (x, z), mass=mass)
    m.gravity(g)
    m.holonomic("floor", [z])
    k = compiled(HybridSystem("held", m))
    lam = k.constraint_forces("held", 0.0, np.array([0.0, 0.0, 1.5, 0.0]), np.array([2.0, 9.81]))
    np.testing.assert_allclose(lam, [2.0 * 9.81], rtol=1e-14)
    np.testing.assert_allclose(k.rhs("held", 0.0, np.array([0.0, 0.0, 1.5, 0.0]), np.array([2.0, 9.81])),
                               [1.5, 0.0, 0.0, 0.0], atol=1e-14)


BIPED_MASSES = {"hip": 10.0, "head": 20.0, "left_thigh": 7.0, "right_thigh": 7.0, "left_shank": 3.0,
                "right_shank": 3.0}
STANCE = 0.25  # the feet are pinned at x = ∓STANCE on the ground (m)


def double_support() -> HybridSystem:
    """A planar five-link biped (hip position, torso and four absolute leg angles from the
    vertical) with both feet held on the ground — two constraints of two equations each — and
    a PD posture law at the hips and knees."""
    m = Model("double-support")
    x, z = m.coordinates("x z", unit="m")
    torso, lt, ls, rt, rs = m.coordinates("torso left_thigh left_shank right_thigh right_shank")
    ml, l_torso, l_thigh, l_shank, g, kp, kd = m.parameters(m_head=BIPED_MASSES["head"], l_torso=0.5, l_thigh=0.45,
                                                            l_shank=0.45, g=9.81, kp=400.0, kd=40.0)
    down = lambda a: sp.Matrix([sp.sin(a), -sp.cos(a)])  # noqa: E731
    hip = m.point("hip", (x, z), mass=BIPED_MASSES["hip"])
    m.point("head", hip - l_torso * down(torso), mass=ml)
    for side, thigh, shank, at in (("left", lt, ls, -STANCE), ("right", rt, rs, STANCE)):
        m.point(f"{side}_thigh", hip + l_thigh / 2 * down(thigh), mass=BIPED_MASSES[f"{side}_thigh"])
        knee = hip + l_thigh * down(thigh)
        m.point(f"{side}_shank", knee + l_shank / 2 * down(shank), mass=BIPED_MASSES[f"{side}_shank"])
        foot = m.point(f"{side}_foot", knee + l_shank * down(shank))
        m.holonomic(f"{side}_foot", [foot[0] - at, foot[1]])  # λ: the ground's force on the foot (x, z)
    m.gravity(g)
    laws = {}
    for name, joint, ref in (("left_hip", lt - torso, -0.4), ("right_hip", rt - torso, 0.25),
                             ("left_knee", ls - lt, 0.0), ("right_knee", rs - rt, 0.0)):
        laws[m.actuator(name, joint)] = -kp * (joint - ref) - kd * m.dt(joint)
    m.control(laws)
    return HybridSystem("double-support", m)


def test_a_biped_in_double_support_obeys_newton_for_its_whole_body():
    """Along the motion the ground's forces (λ) and gravity accelerate the centre of mass:
    ``Σλ + m g = Σ mᵢ aᵢ``, the accelerations taken from the recorded positions of the masses
    (second differences, Richardson-extrapolated); at rest the feet carry the weight, with the
    centre of pressure under the centre of mass."""
    a = -0.35  # left thigh; the legs mirror each other and the torso leans 0.2 rad forward
    b = np.arcsin((-STANCE - 0.45 * np.sin(a)) / 0.45)
    x0 = np.array([0.0, 0.45 * (np.cos(a) + np.cos(b)), 0.2, a, b, -a, -b] + [0.0] * 7)
    system = double_support()
    dt = 5e-4
    traj = simulate(system, x0, t_end=1.0, sample_dt=dt, rtol=1e-12, atol=1e-12)
    pts, lam = traj.points(), traj.constraint_forces()
    for side, at in (("left", -STANCE), ("right", STANCE)):
        assert np.max(np.abs(pts[f"{side}_foot"][:, [0, 2]] - [at, 0.0])) <= 1e-10

    def second_difference(step: int) -> np.ndarray:
        n = len(traj.t)
        return sum(mass * (p[2 + step:n - 2 + step] - 2 * p[2:n - 2] + p[2 - step:n - 2 - step]) / (step * dt) ** 2
                   for p, mass in ((pts[k], v) for k, v in BIPED_MASSES.items()))

    ma = (4 * second_difference(1) - second_difference(2)) / 3  # Σ mᵢ aᵢ, error O(dt⁴)
    force = np.column_stack([lam["left_foot[0]"] + lam["right_foot[0]"],
                             lam["left_foot[1]"] + lam["right_foot[1]"] - sum(BIPED_MASSES.values()) * 9.81])
    assert np.max(np.abs(ma[:, [0, 2]])) > 100.0  # the posture law moves the body
    assert np.max(np.abs(force[2:-2] - ma[:, [0, 2]])) <= 1e-5 * np.max(np.abs(ma))
    rest = simulate(system, x0, t_end=4.0, sample_dt=0.01)
    lam, pts = rest.constraint_forces(), rest.points()
    assert np.max(np.abs(rest.x[-1, 7:])) < 1e-8
    weight = sum(BIPED_MASSES.values()) * 9.81
    vertical = lam["left_foot[1]"][-1] + lam["right_foot[1]"][-1]
    assert vertical == pytest.approx(weight, rel=1e-9)
    com = sum(mass * pts[k][-1, 0] for k, mass in BIPED_MASSES.items()) / sum(BIPED_MASSES.values())
    cop = (-STANCE * lam["left_foot[1]"][-1] + STANCE * lam["right_foot[1]"][-1]) / vertical
    assert abs(com) > 0.01  # the law's asymmetric posture: not a symmetric stance
    assert cop == pytest.approx(com, abs=1e-9)


def test_the_equations_command_shows_the_constraints(tmp_path, capsys):
    from amble.cli.main import main

    path = tmp_path / "held.py"
    path.write_text('from amble import HybridSystem, Model\n'
                    'm = Model("held")\nx, z = m.coordinates("x z", unit="m")\n'
                    'm.point("p", (x, z), mass=1.0)\nm.gravity(9.81)\nm.holonomic("rod", ["x**2 + z**2 - 1"])\n'
                    'system = HybridSystem("held", m)\n')
    assert main(["equations", str(path)]) == 0
    assert "constraint rod: x**2 + z**2 - 1 = 0" in capsys.readouterr().out


def test_a_block_lifts_off_when_its_floor_force_falls_through_zero():
    """A block sliding at speed v on the floor (z = 0) and pulled up by k x: λ = m g − k x
    (holonomic_forces) crosses zero at t* = m g / (k v), where a guard on it switches to flight;
    then z = k v (t − t*)³ / (6 m)."""
    from amble import Explicit, Guard, holonomic_forces

    def block(held: bool) -> Model:
        m = Model("held" if held else "free")
        x, z = m.coordinates("x z", unit="m")
        mass, g, k = m.parameters(mass=2.0, g=9.81, k=4.0)
        m.point("p", (x, z), mass=mass)
        m.gravity(g)
        m.force([0, k * x])
        if held:
            m.holonomic("floor", [z])
        return m

    held, free = block(True), block(False)
    lam = holonomic_forces(held)["floor"]
    mass, g, k = held.params
    assert sp.simplify(lam - (mass * g - k * held.q[0])) == 0
    system = HybridSystem("lift", {"held": held, "free": free})
    system.transition("liftoff", "held", Guard(lam, direction=-1), Explicit(q=held.q, qd=held.qd), "free")
    v = 0.5
    traj = simulate(system, [0.0, 0.0, v, 0.0], t_end=12.0, rtol=1e-12, atol=1e-12)
    t_star = 2.0 * 9.81 / (4.0 * v)
    (lift,) = [e for e in traj.events if e.name == "liftoff"]
    assert lift.t == pytest.approx(t_star, abs=1e-10)
    assert traj.final_state[1] == pytest.approx(4.0 * v * (12.0 - t_star) ** 3 / 12.0, rel=1e-9)
    kernels = compiled(system)
    np.testing.assert_allclose(kernels.constraint_forces("held", 0.0, [1.0, 0.0, v, 0.0], [2.0, 9.81, 4.0]),
                               [2.0 * 9.81 - 4.0], rtol=1e-14)
