"""Resting contact: a unilateral contact declared with ``unilateral_contact`` bounces
with restitution, comes to rest in its constrained mode when the impacts accumulate (or at once
with e = 0), and lifts off when the contact force would turn negative. Closed forms: the Zeno
time of a bouncing ball, free fall, and the force of a point held on a table."""

import json
import math

import numpy as np
import pytest
import sympy as sp

import amble
from amble import HybridSystem, Model, ModelError, t

G = 9.81


def _ball(name: str, table=None):
    m = Model(name)
    x, z = m.coordinates("x z")
    mass, g, e, jerk = m.parameters(mass=2.0, g=G, e=0.5, jerk=4.0)
    m.point("p", (x, z), mass=mass)
    m.gravity(g)
    s = HybridSystem(name, m)
    gap = z if table is None else z - table(jerk)
    amble.unilateral_contact(s, "floor", name, gap, e)
    return s, m, gap


@pytest.mark.parametrize("e", [0.5, 0.7])
def test_a_bouncing_ball_rests_at_the_zeno_time_and_the_run_continues(e):
    s, _, _ = _ball("rc-ball")
    h = 1.0
    tr = amble.simulate(s, [0.0, h, 0.0, 0.0], params={"e": e}, t_end=6.0)
    assert tr.status == "end_time", tr.message
    t_zeno = math.sqrt(2 * h / G) * (1 + 2 * e / (1 - e))
    rest = [ev for ev in tr.events if ev.name == "floor_rest"]
    assert len(rest) == 1 and rest[0].target == "rc-ball_floor"
    assert rest[0].t == pytest.approx(t_zeno, rel=1e-6)
    after = tr.t > rest[0].t
    assert after.sum() > 1 and tr.t[-1] == pytest.approx(6.0)
    assert np.max(np.abs(tr.x[after, 1])) < 1e-9 and np.max(np.abs(tr.x[after, 3])) < 1e-9


def test_the_resting_force_is_the_weight():
    _, m, gap = _ball("rc-ball")
    mass, g = sp.Symbol("mass", real=True), sp.Symbol("g", real=True)
    lam = amble.contact_force(m, gap)
    assert sp.simplify(lam - mass * g) == 0


def test_restitution_zero_lands_and_rests_at_once():
    s, _, _ = _ball("rc-ball")
    tr = amble.simulate(s, [0.0, 1.0, 0.0, 0.0], params={"e": 0.0}, t_end=3.0)
    assert tr.status == "end_time", tr.message
    assert [ev.name for ev in tr.events] == ["floor", "floor_rest"]
    assert tr.events[-1].t == pytest.approx(math.sqrt(2 / G), abs=1e-9)
    assert abs(tr.final_state[1]) < 1e-12 and tr.final_state[3] == 0.0


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_a_point_released_on_the_floor_stays_on_it_and_slides(e):
    s, _, _ = _ball("rc-ball")
    tr = amble.simulate(s, [0.0, 0.0, 0.3, 0.0], params={"e": e}, t_end=3.0)
    assert tr.status == "end_time", tr.message
    assert tr.events[-1].name == "floor_rest" and tr.events[-1].t < 1e-12
    x, z, xd, zd = tr.final_state
    assert x == pytest.approx(0.9, rel=1e-12) and abs(z) < 1e-12 and zd == 0.0


def test_a_table_accelerating_down_faster_than_g_lets_the_ball_lift_off():
    # the table's height −j t³/6: its acceleration −j t exceeds g from t* = g/j on, where the
    # contact force m (g − j t) turns negative; after that the ball falls freely
    s, m, gap = _ball("rc-table", table=lambda j: -j * t**3 / 6)
    jerk = 4.0
    mass, g, j = (sp.Symbol(n, real=True) for n in ("mass", "g", "jerk"))
    assert sp.simplify(amble.contact_force(m, gap) - mass * (g - j * t)) == 0
    t_end = 4.0
    tr = amble.simulate(s, [0.0, 0.0, 0.0, 0.0], t_end=t_end)
    assert tr.status == "end_time", tr.message
    assert [ev.name for ev in tr.events][-2:] == ["floor_rest", "floor_liftoff"]
    ts = G / jerk
    assert tr.events[-1].t == pytest.approx(ts, abs=1e-9)
    zs, vs = -jerk * ts**3 / 6, -jerk * ts**2 / 2
    assert tr.events[-1].x_pre[1] == pytest.approx(zs, rel=1e-9)
    tau = t_end - ts
    assert tr.final_state[1] == pytest.approx(zs + vs * tau - G / 2 * tau**2, rel=1e-9)
    assert tr.final_state[3] == pytest.approx(vs - G * tau, rel=1e-9)


def test_bad_contacts_are_model_errors():
    m = Model("rc-bad")
    x, z = m.coordinates("x z")
    m.point("p", (x, z), mass=1.0)
    s = HybridSystem("rc-bad", m)
    with pytest.raises(ModelError, match="restitution"):
        amble.unilateral_contact(s, "floor", "rc-bad", z, 1.5)
    with pytest.raises(ModelError, match="does not depend"):
        amble.unilateral_contact(s, "floor", "rc-bad", sp.Integer(1), 0.5)
    with pytest.raises(ModelError, match="unknown mode"):
        amble.unilateral_contact(s, "floor", "nope", z, 0.5)
    amble.unilateral_contact(s, "floor", "rc-bad", z, 0.5)
    with pytest.raises(ModelError, match="exists already"):
        amble.unilateral_contact(s, "floor", "rc-bad", z, 0.5)


def test_a_run_with_sensitivities_ends_as_zeno_at_the_rest_transition():
    # the rest transition carries no saltation matrix: the run says where it stopped instead
    from amble.backend.kernels import build
    from amble.simulation.engine import Options, run
    from amble.simulation.simulate import parameter_vector

    s, _, _ = _ball("rc-ball")
    k = build(s, derivatives=True)
    p = parameter_vector(k, {"e": 0.0}, s)
    r = run(k, p, 0, np.array([0.0, 1.0, 0.0, 0.0]), t_end=3.0, opts=Options(), sensitivities=True)
    assert r.status == "zeno"
    assert r.t == pytest.approx(math.sqrt(2 / G), abs=1e-9)


def test_a_point_released_on_an_incline_slides_down_it():
    # gap along the unit normal of a frictionless plane descending along +x at angle γ: the point
    # stays on it, slides with acceleration g sin γ and is held by m g cos γ
    m = Model("rc-incline")
    x, z = m.coordinates("x z")
    mass, g, e, gamma = m.parameters(mass=2.0, g=G, e=0.3, gamma=0.3)
    m.point("p", (x, z), mass=mass)
    m.gravity(g)
    s = HybridSystem("rc-incline", m)
    gap = z * sp.cos(gamma) + x * sp.sin(gamma)
    amble.unilateral_contact(s, "plane", "rc-incline", gap, e)
    assert sp.simplify(amble.contact_force(m, gap) - mass * g * sp.cos(gamma)) == 0
    tr = amble.simulate(s, [0.0, 0.0, 0.0, 0.0], t_end=2.0)
    assert tr.status == "end_time", tr.message
    assert tr.events[-1].name == "plane_rest"
    dist = 0.5 * G * math.sin(0.3) * 2.0**2
    xe, ze, _, _ = tr.final_state
    assert xe == pytest.approx(dist * math.cos(0.3), rel=1e-9)
    assert ze == pytest.approx(-dist * math.sin(0.3), rel=1e-9)


@pytest.mark.parametrize("e", [1.0, 0.6])
def test_the_impact_of_a_tumbling_rod_obeys_restitution_and_momentum(e):
    # a rod of two point masses whose end A hits the floor: the impulse acts at A along the
    # normal, so the horizontal momentum and the angular momentum about A are conserved, A's
    # normal velocity becomes −e times what it was, and with e = 1 the kinetic energy is kept
    m = Model("rc-rod")
    xc, zc, th = m.coordinates("xc zc th")
    mass, length, g, ee = m.parameters(mass=1.0, length=0.8, g=G, e=0.5)
    a = (xc - length / 2 * sp.cos(th), zc - length / 2 * sp.sin(th))
    b = (xc + length / 2 * sp.cos(th), zc + length / 2 * sp.sin(th))
    m.point("A", a, mass=mass)
    m.point("B", b, mass=mass)
    m.gravity(g)
    s = HybridSystem("rc-rod", m)
    amble.unilateral_contact(s, "floor", "rc-rod", a[1], ee)
    tr = amble.simulate(s, [0.0, 1.0, 0.6, 0.4, 0.0, 1.5], params={"e": e}, t_end=1.0)
    ev = next(ev for ev in tr.events if ev.name == "floor")
    L, mm = 0.8, 1.0

    def points(x):
        X, Z, T, Xd, Zd, Td = x
        c, sn = math.cos(T), math.sin(T)
        pa, va = np.array([X - L / 2 * c, Z - L / 2 * sn]), np.array([Xd + L / 2 * sn * Td, Zd - L / 2 * c * Td])
        pb, vb = np.array([X + L / 2 * c, Z + L / 2 * sn]), np.array([Xd - L / 2 * sn * Td, Zd + L / 2 * c * Td])
        return (pa, va), (pb, vb)

    def laws(x, about):
        (pa, va), (pb, vb) = points(x)
        px = mm * (va[0] + vb[0])
        ang = sum(mm * ((p - about)[0] * v[1] - (p - about)[1] * v[0]) for p, v in ((pa, va), (pb, vb)))
        kin = 0.5 * mm * (va @ va + vb @ vb)
        return px, ang, kin, va[1]

    contact = points(ev.x_pre)[0][0]
    px0, h0, k0, vn0 = laws(ev.x_pre, contact)
    px1, h1, k1, vn1 = laws(ev.x_post, contact)
    assert vn0 < 0 and vn1 == pytest.approx(-e * vn0, rel=1e-12)
    assert px1 == pytest.approx(px0, abs=1e-12) and h1 == pytest.approx(h0, rel=1e-12)
    if e == 1.0:
        assert k1 == pytest.approx(k0, rel=1e-12)
    else:
        assert k1 < k0


@pytest.mark.parametrize("opts", [amble.Options(method="radau"), amble.Options(zeno_events=0)],
                         ids=["radau", "no-zeno-detector"])
def test_the_ball_rests_with_the_implicit_integrator_and_without_the_zeno_detector(opts):
    # without the detector the bounces go on until one leaves no normal velocity: that is the
    # Zeno point itself, to round-off
    s, _, _ = _ball("rc-ball")
    tr = amble.simulate(s, [0.0, 1.0, 0.0, 0.0], t_end=3.0, options=opts)
    assert tr.status == "end_time", tr.message
    rest = [ev for ev in tr.events if ev.name == "floor_rest"]
    t_zeno = math.sqrt(2 / G) * 3
    assert rest[0].t == pytest.approx(t_zeno, rel=1e-9 if opts.zeno_events == 0 else 1e-6)
    assert abs(tr.final_state[1]) < 1e-12 and tr.final_state[3] == 0.0


def test_a_plastic_landing_on_a_table_falling_faster_than_g_does_not_stick():
    # dropped from 30 m, the ball meets the table (height −j t³/6) after t = g/j, when the table
    # accelerates down faster than g: with e = 0 it takes the table's velocity and then falls
    # freely behind it, never to touch again (held there, it would need a pulling force)
    s, _, _ = _ball("rc-table", table=lambda j: -j * t**3 / 6)
    jerk, z0, t_end = 4.0, 30.0, 6.0
    tr = amble.simulate(s, [0.0, z0, 0.0, 0.0], params={"e": 0.0}, t_end=t_end)
    assert tr.status == "end_time", tr.message
    assert [ev.name for ev in tr.events] == ["floor"]
    ti = tr.events[0].t
    assert z0 - G * ti**2 / 2 == pytest.approx(-jerk * ti**3 / 6, abs=1e-9) and jerk * ti > G
    zi, vi = -jerk * ti**3 / 6, -jerk * ti**2 / 2
    assert tr.events[0].x_post[3] == pytest.approx(vi, rel=1e-12)
    tau = t_end - ti
    assert tr.final_state[1] == pytest.approx(zi + vi * tau - G / 2 * tau**2, rel=1e-9)


def test_a_rod_resting_on_one_end_falls_with_its_energy_and_centre_line_kept():
    # a rod of two point masses standing on end A of a frictionless floor, released at rest:
    # held by the derived contact force, A slides, the centre falls straight down (no horizontal
    # force) and the energy is conserved (the static floor does no work)
    m = Model("rc-rod")
    xc, zc, th = m.coordinates("xc zc th")
    mass, length, g, ee = m.parameters(mass=1.0, length=0.8, g=G, e=0.5)
    a = (xc - length / 2 * sp.cos(th), zc - length / 2 * sp.sin(th))
    m.point("A", a, mass=mass)
    m.point("B", (xc + length / 2 * sp.cos(th), zc + length / 2 * sp.sin(th)), mass=mass)
    m.gravity(g)
    s = HybridSystem("rc-rod", m)
    amble.unilateral_contact(s, "floor", "rc-rod", a[1], ee)
    th0 = 1.4
    tr = amble.simulate(s, [0.4 * math.cos(th0), 0.4 * math.sin(th0), th0, 0.0, 0.0, 0.0], t_end=0.6)
    assert tr.status == "end_time", tr.message
    assert [ev.name for ev in tr.events] == ["floor", "floor_rest"]
    held = tr.t > tr.events[-1].t
    assert tr.x[-1, 2] < 0.5  # it has fallen most of the way
    assert np.max(np.abs(tr.x[held, 0] - 0.4 * math.cos(th0))) < 1e-9
    assert np.max(np.abs(tr.x[held, 1] - 0.4 * np.sin(tr.x[held, 2]))) < 1e-8
    total = tr.energy().sum(axis=1)
    assert np.ptp(total[held]) < 1e-8 * (2 * 1.0 * G * 0.4)


BALL_FILE = """
import amble
from amble import HybridSystem, Model
m = Model("ball")
x, z = m.coordinates("x z")
mass, g, e = m.parameters(mass=1.0, g=9.81, e=0.5)
m.point("p", (x, z), mass=mass)
m.gravity(g)
system = HybridSystem("bouncing-ball", m)
amble.unilateral_contact(system, "floor", "ball", z, e)
"""


def test_the_command_line_shows_the_resting_mode_and_runs_a_contact(tmp_path, capsys):
    from amble.cli.main import main

    f = tmp_path / "ball.py"
    f.write_text(BALL_FILE)
    assert main(["equations", str(f)]) == 0
    out = capsys.readouterr().out
    assert "mode ball_floor" in out and "transition floor_rest: ball -> ball_floor" in out
    assert "guard: none, taken when" in out and "guard: g*mass, falling" in out
    assert main(["simulate", str(f), "--time", "2", "--start", "x0=0,1,0,0", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["status"] == "end_time", res
