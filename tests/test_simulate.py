"""The hybrid engine against closed forms and conservation laws."""

import math

import numpy as np
import pytest

import amble
from amble import Explicit, Guard, HybridSystem, Model


def _falling_mass():
    m = Model("falling-mass")
    x, z = m.coordinates("x z")
    mass, g = m.parameters(mass=1.0, g=9.81)
    m.point("p", (x, z), mass=mass)
    m.gravity(g)
    return m


def test_falling_point_mass_lands_at_closed_form_time():
    m = _falling_mass()
    x, z = m.q
    sys_ = HybridSystem("falling-mass", m)
    sys_.terminal("landed", "falling-mass", Guard(z, -1), status="landed")
    h, g = 2.0, 9.81
    tr = amble.simulate(sys_, [0.0, h, 0.3, 0.0], t_end=10.0)
    assert tr.status == "landed"
    assert abs(tr.events[-1].t - math.sqrt(2 * h / g)) <= 1e-10


def test_two_crossings_inside_one_integration_step_are_found():
    # A free particle moves at constant speed: DOP853 integrates it exactly, so its steps grow
    # by the maximum factor and soon span the whole window 1 < x < 1.3 where the guard
    # (x − 1)(x − 1.3) is negative — both crossings lie inside one step and the guard is
    # positive at both step ends.
    m = Model("free")
    (x,) = m.coordinates("x")
    m.point("p", (x, 0), mass=1)
    sys_ = HybridSystem("free", m)
    sys_.terminal("window", "free", Guard((x - 1) * (x - 1.3), -1), status="hit")
    tr = amble.simulate(sys_, [0.0, 1.0], t_end=100.0, sample_dt=0.0)
    steps = np.diff(tr.t)
    assert steps.max() > 0.3  # some integration step is wider than the window...
    assert tr.status == "hit"  # ...and the entry into it is still found, exactly
    assert abs(tr.events[-1].t - 1.0) <= 1e-10


def test_bouncing_ball_with_restitution_ends_as_zeno():
    m = _falling_mass()
    x, z = m.q
    xd, zd = m.qd
    (e,) = (m.parameter("e", 0.5),)
    sys_ = HybridSystem("ball", m)
    sys_.transition("bounce", "falling-mass", Guard(z, -1), Explicit(q=[x, z], qd=[xd, -e * zd]))
    tr = amble.simulate(sys_, [0.0, 1.0, 0.0, 0.0], t_end=100.0)
    assert tr.status == "zeno"
    # the bounces accumulate at t* = t1 (1 + 2e/(1 − e)), t1 = √(2h/g)
    t1 = math.sqrt(2 / 9.81)
    assert abs(tr.t[-1] - t1 * (1 + 2 * 0.5 / 0.5)) < 1e-3


def test_energy_is_conserved_during_a_passive_swing(compass):
    tr = amble.simulate(compass, steps=2, rtol=1e-13, atol=1e-13, sample_dt=0.005)
    e = tr.energy().sum(axis=1)
    # between the two footfalls (one whole swing phase), excluding impact rows
    t1, t2 = tr.step_events[0].t, tr.step_events[1].t
    sel = (tr.t > t1) & (tr.t < t2)
    seg = e[sel]
    assert sel.sum() > 50
    assert np.max(np.abs(seg - seg[0])) / abs(seg[0]) <= 1e-9


def test_compass_gait_walks_and_converges(compass):
    tr = amble.simulate(compass, [-0.25, 0.35, 1.2, 0.5], steps=40)
    assert tr.status == "completed" and tr.steps == 40
    posts = np.array([e.x_post for e in tr.step_events])
    # the post-impact states converge: late steps barely differ
    assert np.max(np.abs(posts[-1] - posts[-2])) < 1e-6 < np.max(np.abs(posts[1] - posts[0]))
    # every post-impact state lies on the section: the new swing foot on the slope
    slope = 0.05
    assert np.allclose(posts[:, 0] + posts[:, 1], 2 * slope, atol=1e-9)


def test_a_walker_that_falls_says_so(compass):
    tr = amble.simulate(compass, [0.0, 0.0, 0.2, 0.0], steps=5)
    assert tr.status == "fell"


def test_trajectory_exports(compass, tmp_path):
    tr = amble.simulate(compass, steps=3)
    for suffix in (".csv", ".parquet", ".npz"):
        path = tr.save(tmp_path / f"walk{suffix}")
        assert path.stat().st_size > 1000
    import pyarrow.parquet as pq

    tab = pq.read_table(tmp_path / "walk.parquet")
    assert {"t", "mode", "stance", "swing_dot", "kinetic_energy"} <= set(tab.column_names)
    times, pts = tr.resample(30)
    assert set(pts) >= {"hip", "swing_foot"} and pts["hip"].shape == (len(times), 3)
    # the world frame moves forward with the footholds
    assert pts["hip"][-1, 0] > 3 * 0.3


def test_bad_inputs_raise_typed_errors(compass):
    with pytest.raises(amble.StateError):
        amble.simulate(compass, [0.1, 0.2], steps=1)
    with pytest.raises(amble.ParameterError, match="nope"):
        amble.simulate(compass, params={"nope": 1.0}, steps=1)
    with pytest.raises(amble.StateError):
        amble.simulate(compass, [np.nan, 0, 0, 0], steps=1)


def test_singular_mass_matrix_is_reported():
    m = Model("degenerate")
    q1, q2 = m.coordinates("q1 q2")
    m.point("p", (q1 + q2, 0), mass=1)  # only q1 + q2 has inertia: M is singular everywhere
    sys_ = HybridSystem("degenerate", m)
    tr = amble.simulate(sys_, [0, 0, 1, 0], t_end=1.0)
    assert tr.status == "singular_mass"


def test_changing_a_default_is_seen_without_recompiling():
    from amble.backend.kernels import compiled

    def system(g):
        m = _falling_mass()
        m.params[m.symbol("g")] = g
        sys_ = HybridSystem("falling-default", m)
        sys_.terminal("landed", "falling-mass", Guard(m.q[1], -1), status="landed")
        return sys_

    a, b = system(9.81), system(1.62)
    assert compiled(a).path == compiled(b).path  # one compiled library...
    ta = amble.simulate(a, [0.0, 1.0, 0.0, 0.0], t_end=5.0).events[-1].t
    tb = amble.simulate(b, [0.0, 1.0, 0.0, 0.0], t_end=5.0).events[-1].t
    assert abs(ta - math.sqrt(2 / 9.81)) < 1e-10 and abs(tb - math.sqrt(2 / 1.62)) < 1e-10  # ...own defaults


def test_grazing_contact_does_not_fire():
    # A ball thrown up to exactly the guard's level touches g = 0 without crossing: no event.
    m = _falling_mass()
    x, z = m.q
    sys_ = HybridSystem("graze", m)
    sys_.terminal("hit", "falling-mass", Guard(-(z - 1.0), +1), status="hit")  # fires on crossing z = 1 upward
    v = math.sqrt(2 * 9.81 * 0.999)  # apex at 0.999 m: below the guard, never crosses
    tr = amble.simulate(sys_, [0.0, 0.0, 0.0, v], t_end=0.5)
    assert tr.status == "end_time" and not tr.events


def test_event_storm_ends_as_zeno_not_a_hang():
    # Restitution 1 with the ball at rest on the ground: every step re-triggers the guard.
    m = _falling_mass()
    x, z = m.q
    xd, zd = m.qd
    sys_ = HybridSystem("storm", m)
    sys_.transition("bounce", "falling-mass", Guard(z, -1), Explicit(q=[x, 0.0], qd=[xd, -0.1 * zd]))
    tr = amble.simulate(sys_, [0.0, 1e-9, 0.0, 0.0], t_end=10.0)
    assert tr.status == "zeno"


def test_blow_up_is_reported_not_passed_on():
    # q̈ = q³ (a potential −q⁴/4) reaches infinity in finite time: the run must end with a status.
    m = Model("blowup")
    (q,) = m.coordinates("q")
    m.point("p", (q, 0), mass=1)
    m.add_potential(-(q**4) / 4)
    tr = amble.simulate(HybridSystem("blowup", m), [1.0, 1.0], t_end=10.0)
    assert tr.status == "integrator_failure"
    assert np.all(np.isfinite(tr.x[:-1]))
