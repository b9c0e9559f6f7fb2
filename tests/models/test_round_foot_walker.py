"""Round-foot walker: the rolling-foot impact against conservation laws computed here with NumPy,
energy over the swing, the point-foot limit r → 0, and the stable gait."""

import numpy as np
import pytest

from amble import Model, R, rolling_centre, round_foot, simulate, walker
from amble.analysis.poincare import find_fixed_point
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.simulate import parameter_vector

#: a lopsided walker on a steeper slope: light hip, heavy feet, big radius, centre of mass low
OTHER = dict(mh=3.0, m=2.0, I=0.05, l=0.6, c=0.45, r=0.45, g=9.81, slope=0.12)


@pytest.fixture(scope="module")
def rfw():
    return load("round-foot-walker")


def values(k, params):
    return dict(zip(k.meta["params"], parameter_vector(k, params)))


def kinematics(x, v):
    """Positions and velocities (x downhill-horizontal, z up; m, m/s) of the walker at state x,
    written out here: the stance foot's arc centre r (θ − γ) d + r n (rolling without slip),
    the hip l above it along the stance leg, the leg masses c below the hip, the swing foot's
    arc centre l below the hip and its lowest point r below that along the slope normal."""
    st, sw, dst, dsw = x
    r, l, c, gam = v["r"], v["l"], v["c"], v["slope"]
    n, d = np.array([np.sin(gam), np.cos(gam)]), np.array([np.cos(gam), -np.sin(gam)])
    e, de = (lambda a: np.array([np.sin(a), np.cos(a)])), (lambda a: np.array([np.cos(a), -np.sin(a)]))
    centre, dcentre = r * (st - gam) * d + r * n, r * dst * d
    hip, dhip = centre + l * e(st), dcentre + l * dst * de(st)
    pos = dict(hip=hip, stance_mass=hip - c * e(st), swing_mass=hip - c * e(sw),
               stance_contact=centre - r * n, swing_contact=hip - l * e(sw) - r * n)
    vel = dict(hip=dhip, stance_mass=dhip - c * dst * de(st), swing_mass=dhip - c * dsw * de(sw))
    return pos, vel


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def momentum_about(x, v, about, legs=None):
    """Angular momentum (kg·m²/s, in the plane; clockwise — the sense in which the angles grow —
    counts negative) about the named point's position of the whole walker, or of the ``legs``
    named: masses r × m v, legs' spins −I θ̇."""
    pos, vel = kinematics(x, v)
    o = pos[about]
    h = v["mh"] * cross(pos["hip"] - o, vel["hip"]) if legs is None else 0.0
    for i, leg in enumerate(("stance", "swing")):
        if legs is None or leg in legs:
            h += v["m"] * cross(pos[f"{leg}_mass"] - o, vel[f"{leg}_mass"]) - v["I"] * x[2 + i]
    return h


def kinetic(x, v):
    vel = kinematics(x, v)[1]
    return 0.5 * (v["mh"] * vel["hip"] @ vel["hip"] + v["m"] * (vel["stance_mass"] @ vel["stance_mass"]
                  + vel["swing_mass"] @ vel["swing_mass"]) + v["I"] * (x[2] ** 2 + x[3] ** 2))


def momentum(x, v):
    """Linear momentum (kg·m/s)."""
    vel = kinematics(x, v)[1]
    return v["mh"] * vel["hip"] + v["m"] * (vel["stance_mass"] + vel["swing_mass"])


def energy(x, v):
    """Kinetic plus potential energy (J), heights from the origin of the state's step frame."""
    pos = kinematics(x, v)[0]
    return kinetic(x, v) + v["g"] * (v["mh"] * pos["hip"][1] + v["m"] * (pos["stance_mass"][1] + pos["swing_mass"][1]))


def footfalls(rng, gamma, count):
    """Pre-impact states at a footfall (legs symmetric about the slope normal, stance ahead of it)."""
    for _ in range(count):
        beta = rng.uniform(0.1, 0.5)
        yield np.array([gamma + beta, gamma - beta, *rng.uniform(-3, 3, 2)])


@pytest.mark.parametrize("params", [None, OTHER])
def test_impact_conserves_angular_momenta_about_the_contact_and_of_the_trailing_leg_about_the_hip(rfw, params):
    # The only external impulse acts at the new contact; the trailing leg's foot lifts off, so the
    # hip pin is the only impulse on that leg.
    k = compiled(rfw)
    p, v = parameter_vector(k, params), values(k, params)
    for x in footfalls(np.random.default_rng(7), v["slope"], 40):
        swing_contact = kinematics(x, v)[0]["swing_contact"]
        assert abs(np.array([np.sin(v["slope"]), np.cos(v["slope"])]) @ swing_contact) < 1e-12  # on the slope
        _, post = k.reset("heel_strike", 0.0, x, p)
        assert np.array_equal(post[:2], x[[1, 0]])
        h0, h1 = momentum_about(x, v, "swing_contact"), momentum_about(post, v, "stance_contact")
        assert h1 == pytest.approx(h0, rel=1e-12, abs=1e-12)
        # the trailing leg: stance before the impact, swing after it
        t0 = momentum_about(x, v, "hip", legs=("stance",))
        t1 = momentum_about(post, v, "hip", legs=("swing",))
        assert t1 == pytest.approx(t0, rel=1e-12, abs=1e-12)
        assert kinetic(post, v) <= kinetic(x, v) + 1e-12  # (the impact moves no mass)


def naive_round_foot_walker():
    """The same walker, but the impact constrains the geometric lowest point of the swing foot's
    arc (``centre − r n``) instead of the material point at the contact."""
    m = Model("naive-round-foot")
    st, sw = m.coordinates("stance swing")
    mh, ml, I, l, c, r, g, slope = m.parameters(mh=10.0, m=5.0, I=0.2042, l=0.7, c=0.35, r=0.3, g=9.81, slope=0.05)
    stance = round_foot(m, "stance_foot", rolling_centre(st, r, slope), st, r, slope)
    hip = m.point("hip", m.points[stance.centre] + l * R(st), mass=mh)
    m.point("stance_mass", hip - c * R(st), mass=ml)
    m.point("swing_mass", hip - c * R(sw), mass=ml)
    swing = round_foot(m, "swing_foot", hip - l * R(sw), sw, r, slope)
    m.inertia(st, I)
    m.inertia(sw, I)
    m.gravity(g)
    return walker(m, foot=swing.contact, stance=stance, hip="hip", slope=slope, relabel={st: sw, sw: st})


def test_an_impact_of_the_lowest_point_instead_of_the_material_point_breaks_conservation():
    # what the check above guards against: the constraint on the geometric point is the wrong impact
    k = compiled(naive_round_foot_walker())
    p, v = parameter_vector(k, None), values(k, None)
    x = next(footfalls(np.random.default_rng(7), v["slope"], 1))
    _, post = k.reset("heel_strike", 0.0, x, p)
    h0, h1 = momentum_about(x, v, "swing_contact"), momentum_about(post, v, "stance_contact")
    assert abs(h1 - h0) > 1e-3 * abs(h0)


@pytest.mark.parametrize("params", [None, OTHER])
def test_energy_is_conserved_over_the_swing_and_lost_at_heel_strike(rfw, params):
    k = compiled(rfw)
    v = values(k, params)
    lc = find_fixed_point(rfw, params=params)
    tr = simulate(rfw, lc.fixed_point, params=params, steps=1)
    assert tr.status == "completed"
    e = np.array([energy(x, v) for x in tr.x])
    assert np.ptp(e[:-1]) < 1e-8 * abs(e[0])  # samples before the impact
    ev = tr.events[0]
    assert kinetic(ev.x_post, v) < kinetic(ev.x_pre, v) - 1e-3
    # the swing foot's arc touches the slope at the footfall, ahead of the stance foot's contact
    pos = kinematics(ev.x_pre, v)[0]
    d = np.array([np.cos(v["slope"]), -np.sin(v["slope"])])
    assert abs(np.array([np.sin(v["slope"]), np.cos(v["slope"])]) @ pos["swing_contact"]) < 1e-10
    assert d @ (pos["swing_contact"] - pos["stance_contact"]) > 0.1
    # a valid footfall: the ground pushes (the impulse, the change of linear momentum, points out
    # of the slope) and the trailing foot's material point leaves the ground
    n = np.array([np.sin(v["slope"]), np.cos(v["slope"])])
    assert n @ (momentum(ev.x_post, v) - momentum(ev.x_pre, v)) > 0
    sw, dsw = ev.x_post[1], ev.x_post[3]
    hip = kinematics(ev.x_post, v)[1]["hip"]
    trailing = hip - v["l"] * dsw * np.array([np.cos(sw), -np.sin(sw)]) - v["r"] * dsw * d  # ċ + ω × (−r n)
    assert n @ trailing > 0


def test_world_positions_are_continuous_through_the_footfall(rfw):
    # the next step's origin is the new stance foot's rolling point: the hip does not jump
    tr = simulate(rfw, steps=3)
    hip = tr.world_points()["hip"]
    jumps = np.abs(np.diff(hip, axis=0)).max(axis=1)
    assert jumps.max() < 0.05
    # and the stance foot's contact moves r Δθ along the slope during a step (rolling, no slip)
    v = values(compiled(rfw), None)
    foot = tr.world_points()["stance_foot"]
    one = tr.t < tr.events[0].t
    travelled = np.linalg.norm(foot[one][-1] - foot[one][0])
    assert travelled == pytest.approx(v["r"] * (tr.x[one][-1, 0] - tr.x[one][0, 0]), rel=1e-9)


def test_stable_limit_cycle_at_the_defaults(rfw):
    lc = find_fixed_point(rfw)
    assert lc.residual < 1e-9 and lc.stable
    st, sw = lc.fixed_point[:2]
    assert st + sw == pytest.approx(2 * 0.05, abs=1e-9)  # both feet on the slope: legs symmetric about the normal
    # the model's stored start is this gait (that the gait is the walker's is checked against an
    # independent SciPy model below)
    np.testing.assert_allclose(lc.fixed_point, rfw.default_start["round-foot-walker"], atol=1e-9)


@pytest.mark.parametrize("slope", [0.05, 0.03])
def test_zero_radius_is_the_compass_gait(rfw, slope):
    # compass gait (thesis Table 2): point-mass legs (I = 0) with the mass a = 0.5 m below the hip
    compass = find_fixed_point(load("compass-gait"), params=dict(slope=slope))
    lc = find_fixed_point(rfw, compass.fixed_point, params=dict(r=0.0, I=0.0, l=1.0, c=0.5, mh=10.0, m=5.0,
                                                                 slope=slope))
    np.testing.assert_allclose(lc.fixed_point, compass.fixed_point, atol=1e-9)
    assert lc.step_time == pytest.approx(compass.step_time, abs=1e-9)
    key = lambda z: (abs(z), z.imag)  # noqa: E731
    np.testing.assert_allclose(sorted(lc.multipliers, key=key), sorted(compass.multipliers, key=key), atol=1e-7)


def test_zero_radius_from_the_default_guess_finds_the_compass_gait_too(rfw):
    lc = find_fixed_point(rfw, params=dict(r=0.0, I=0.0, l=1.0, c=0.5))
    # the compass gait at slope 0.05: Goswami et al.'s equations integrated by SciPy
    # (tests/oracles/compass_gait.py), in our coordinates
    from oracles.compass_gait import fixed_point

    x = fixed_point(0.05)[0]
    np.testing.assert_allclose(lc.fixed_point, [-x[1], -x[0], -x[3], -x[2]], rtol=0, atol=1e-9)


def scipy_walker(v):
    """The walker written again from scratch: Lagrange's equations by SymPy from the kinematics
    above, SciPy's DOP853 with event location, and the impact solved from the two conservation
    laws (angular momentum about the contact, trailing leg about the hip) — linear in the
    post-impact velocities. Returns the stride map of the section (stance, stance_dot, swing_dot)
    and the step time."""
    import sympy as sp
    from scipy.integrate import solve_ivp

    q, qd = sp.symbols("q0 q1", real=True), sp.symbols("u0 u1", real=True)
    gam, r, l, c = (v[k] for k in ("slope", "r", "l", "c"))
    n, d = sp.Matrix([np.sin(gam), np.cos(gam)]), sp.Matrix([np.cos(gam), -np.sin(gam)])
    e = lambda a: sp.Matrix([sp.sin(a), sp.cos(a)])  # noqa: E731
    hip = r * (q[0] - gam) * d + r * n + l * e(q[0])
    masses = [(v["mh"], hip), (v["m"], hip - c * e(q[0])), (v["m"], hip - c * e(q[1]))]
    vel = lambda p: p.jacobian(q) * sp.Matrix(qd)  # noqa: E731
    K = sum(mi * (vel(p).T * vel(p))[0] / 2 for mi, p in masses) + v["I"] * (qd[0] ** 2 + qd[1] ** 2) / 2
    V = sum(mi * v["g"] * p[1] for mi, p in masses)
    L = K - V
    M = sp.Matrix(2, 2, lambda i, j: sp.diff(L, qd[i], qd[j]))
    rest = sp.Matrix([sum(sp.diff(L, qd[i], q[j]) * qd[j] for j in range(2)) - sp.diff(L, q[i]) for i in range(2)])
    acc = sp.lambdify([q, qd], M.LUsolve(-rest))

    def height(t, x):
        return float(np.array([np.sin(gam), np.cos(gam)]) @ kinematics(x, v)[0]["swing_contact"])

    def ahead(t, x):  # the swing foot's contact 0.1 m ahead of the stance foot's
        pos = kinematics(x, v)[0]
        return float(np.array([np.cos(gam), -np.sin(gam)]) @ (pos["swing_contact"] - pos["stance_contact"])) - 0.1

    height.terminal, height.direction, ahead.terminal, ahead.direction = True, -1, True, 1
    rhs = lambda t, x: np.concatenate([x[2:], np.ravel(acc(x[:2], x[2:]))])  # noqa: E731
    tol = dict(method="DOP853", rtol=1e-12, atol=1e-12)

    def impact(x):
        def linear(f):  # the matrix of a function linear in the velocities
            return np.array([[f(np.array([*x[[1, 0]], *b])) for b in np.eye(2)]]).reshape(2)
        rows = [linear(lambda y: momentum_about(y, v, "stance_contact")),
                linear(lambda y: momentum_about(y, v, "hip", legs=("swing",)))]
        rhs_ = [momentum_about(x, v, "swing_contact"), momentum_about(x, v, "hip", legs=("stance",))]
        return np.array([*x[[1, 0]], *np.linalg.solve(np.array(rows), rhs_)])

    def stride(y):
        x = np.array([y[0], 2 * gam - y[0], y[1], y[2]])
        a = solve_ivp(rhs, (0, 5), x, events=ahead, **tol)
        b = solve_ivp(rhs, (a.t[-1], 5), a.y[:, -1], events=height, **tol)
        post = impact(b.y_events[0][0])
        return post[[0, 2, 3]], b.t_events[0][0]

    return stride


@pytest.mark.parametrize("params", [None, pytest.param(OTHER, marks=pytest.mark.slow)])
def test_fixed_point_and_multipliers_agree_with_an_independent_scipy_model(rfw, params):
    lc = find_fixed_point(rfw, params=params)
    stride = scipy_walker(values(compiled(rfw), params))
    y = lc.fixed_point[[0, 2, 3]]
    image, step_time = stride(y)
    np.testing.assert_allclose(image, y, rtol=0, atol=1e-9)  # amble's fixed point is one of SciPy's map
    assert step_time == pytest.approx(lc.step_time, abs=1e-9)
    h = 1e-5  # central differences of SciPy's map: the multipliers
    jac = np.array([(stride(y + h * b)[0] - stride(y - h * b)[0]) / (2 * h) for b in np.eye(3)]).T
    key = lambda z: (abs(z), z.imag)  # noqa: E731
    np.testing.assert_allclose(sorted(np.linalg.eigvals(jac), key=key), sorted(lc.multipliers, key=key), atol=1e-6)


def test_the_rolling_point_moves_with_the_material_point_at_the_contact():
    # v = ċ + ω × (−r n), the cross product taken in 3D (x, y, z): the plane's angles turn about +y
    # (R(θ) is the vertical (0, 0, 1) turned by θ about +y, leaning toward +x)
    import sympy as sp

    m = Model("disc")
    (th,) = m.coordinates("theta")
    r, gam, x0 = m.parameters(r=0.3, slope=0.1, x0=0.2)
    foot = round_foot(m, "foot", sp.Matrix([x0, 1]) + 0.5 * R(th), th, r, gam)
    centre = m.points[foot.centre]
    vc = m.jacobian(centre) * sp.Matrix([m.dot(th)])
    omega = sp.Matrix([0, m.dot(th), 0])
    arm = -r * sp.Matrix([sp.sin(gam), 0, sp.cos(gam)])
    v3 = sp.Matrix([vc[0], 0, vc[1]]) + omega.cross(arm)
    v = m.jacobian(m.points[foot.rolling]) * sp.Matrix([m.dot(th)])
    assert sp.simplify(v - sp.Matrix([v3[0], v3[2]])) == sp.zeros(2, 1)
    # while the lowest point of the arc moves with the centre only
    lowest = m.jacobian(m.points[foot.contact]) * sp.Matrix([m.dot(th)])
    assert sp.simplify(lowest - vc) == sp.zeros(2, 1)


def test_a_rolling_stance_foot_advances_r_dtheta_and_its_material_point_is_at_rest():
    import sympy as sp

    m = Model("wheel")
    (th,) = m.coordinates("theta")
    r, gam = m.parameters(r=0.3, slope=0.1)
    foot = round_foot(m, "foot", rolling_centre(th, r, gam), th, r, gam)
    contact = m.points[foot.contact]
    downhill = sp.Matrix([sp.cos(gam), -sp.sin(gam)])
    assert sp.simplify((downhill.T * sp.diff(contact, th))[0] - r) == 0  # d(contact)/dθ = r along the slope
    assert sp.simplify(sp.Matrix([sp.sin(gam), sp.cos(gam)]).T * contact)[0] == 0  # on the slope
    assert sp.simplify(m.points[foot.rolling]) == sp.zeros(2, 1)


def test_round_feet_are_planar():
    from amble import ModelError

    m = Model("spatial", dims=3)
    (th,) = m.coordinates("theta")
    with pytest.raises(ModelError, match="planar"):
        round_foot(m, "foot", (0, 0, 1), th, 0.1, 0.0)


def test_the_default_search_finds_the_gait_in_other_units_and_time_scales_as_sqrt_l_over_g(rfw):
    # a light walker in units where g = 1 (most of the mass at the hip, as McGeer's): gravity only
    # sets the time scale, so the angles stay, rates scale with √g and the step time with 1/√g
    light = dict(mh=0.68, m=0.16, I=0.16 * 0.35**2, l=0.7, c=0.35, r=0.3, slope=0.025)
    unit = find_fixed_point(rfw, params=dict(light, g=1.0))
    si = find_fixed_point(rfw, unit.fixed_point * [1, 1, 9.81**0.5, 9.81**0.5], params=dict(light, g=9.81))
    assert unit.stable and si.stable
    np.testing.assert_allclose(si.fixed_point, unit.fixed_point * [1, 1, 9.81**0.5, 9.81**0.5], atol=1e-9)
    assert si.step_time * 9.81**0.5 == pytest.approx(unit.step_time, abs=1e-9)
