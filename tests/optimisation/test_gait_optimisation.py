"""Gait optimisation against known truth: the passive compass gait (its effort-free optimum),
conservation of angular momentum through the impact, closed-form kinematics and limits."""

import numpy as np
import pytest

pytest.importorskip("casadi")

from amble import simulate  # noqa: E402
from amble.analysis.gait_optimisation import optimize_gait  # noqa: E402
from amble.analysis.gait_result import bernstein  # noqa: E402
from amble.analysis.poincare import find_fixed_point  # noqa: E402
from amble.errors import ParameterError, SolverError  # noqa: E402
from amble.models import compass_gait, load  # noqa: E402

SLOPE = 0.0524  # 3°
P = dict(mh=10.0, m=5.0, a=0.5, b=0.5, g=9.81)


def actuated_compass(hip_limit=40.0, ankle=True):
    """The library's compass gait, built afresh (``load`` shares one per process), with a hip torque
    (and an ankle torque on the stance leg)."""
    s = compass_gait.build()
    m = s.modes["compass-gait"]
    st, sw = m.q
    m.actuator("hip", on=sw - st, limit=hip_limit)
    if ankle:
        m.actuator("ankle", on=st, limit=20.0)
    return s


@pytest.fixture(scope="module")
def passive_optimum():
    s = actuated_compass()
    return s, optimize_gait(s, params={"slope": SLOPE}, objective="effort", nodes=30)


def test_effort_optimum_on_a_slope_is_the_passive_gait(passive_optimum):
    _, g = passive_optimum
    lc = find_fixed_point(load("compass-gait"), params={"slope": SLOPE})
    assert g.objective < 1e-10 and np.abs(g.inputs).max() < 1e-5
    assert np.abs(g.fixed_point - lc.fixed_point).max() <= 1e-6
    assert g.step_time == pytest.approx(lc.step_time, abs=1e-6)
    assert g.max_violation <= 1e-8


def test_passive_simulation_reproduces_the_collocated_step(passive_optimum):
    """Walking the optimised gait (inputs ≈ 0: the passive system) from its fixed point: the
    step follows the collocation solution, and Newton from it converges on the exact return map."""
    s, g = passive_optimum
    passive = load("compass-gait")
    tr = simulate(passive, g.fixed_point, params={"slope": SLOPE}, steps=1, sample_dt=0.005)
    ev = tr.step_events[0]
    inside = tr.t < min(ev.t, g.step_time)  # rows of the step itself (the event's time holds pre and post)
    assert inside.sum() > 100
    assert np.abs(tr.x[inside] - g.state(tr.t[inside])).max() <= 1e-4
    assert ev.t == pytest.approx(g.step_time, abs=1e-5)
    assert np.abs(ev.x_pre - g.pre_impact_state).max() <= 1e-4
    lc = find_fixed_point(passive, g.fixed_point, params={"slope": SLOPE})
    assert lc.residual <= 1e-8 and np.abs(lc.fixed_point - g.fixed_point).max() <= 1e-6


def test_contact_force_matches_the_gait_check_of_the_simulated_step(passive_optimum):
    """The stance-foot force the NLP constrains against the ground reaction that
    amble.analysis.gait_check computes from the simulated step (its own NumPy code, the
    accelerations from the compiled right-hand side)."""
    from amble.analysis.gait_check import ground_reaction

    _, g = passive_optimum
    tr = simulate(load("compass-gait"), g.fixed_point, params={"slope": SLOPE}, steps=1, sample_dt=0.01)
    F, _, _ = ground_reaction(tr)
    inside = tr.t < min(tr.step_events[0].t, g.step_time)
    ours = np.column_stack([np.interp(tr.t[inside], g.times, g.contact_forces[:, i]) for i in range(2)])
    assert np.abs(ours - F[inside][:, [0, 2]]).max() <= 1e-2 * np.abs(F[inside]).max()
    assert g.contact_forces[:, 1].min() > 0  # the ground pushes up throughout the step


def _momenta(x, l, a, b, m, mh):
    """Closed-form compass gait (Drake's angles): total angular momentum about the swing foot, and
    each leg's about the hip (absolute velocities), in the frame of the stance foot."""
    st, sw, dst, dsw = x
    e = lambda th: np.array([np.sin(th), np.cos(th)])
    de = lambda th, w: w * np.array([np.cos(th), -np.sin(th)])
    hip, vhip = l * e(st), l * de(st, dst)
    foot = hip - l * e(sw)
    masses = [(mh, hip, vhip), (m, b * e(st), b * de(st, dst)), (m, hip - a * e(sw), vhip - a * de(sw, dsw))]
    cross = lambda r, v: r[0] * v[1] - r[1] * v[0]
    total = sum(mi * cross(r - foot, v) for mi, r, v in masses)
    swing = m * cross(-a * e(sw), vhip - a * de(sw, dsw))
    stance = m * cross(b * e(st) - hip, b * de(st, dst))
    return total, swing, stance


def test_derived_impact_in_the_gait_conserves_angular_momentum(passive_optimum):
    """Through the plastic impact the angular momentum about the new stance foot is conserved, and
    so is the trailing (old stance) leg's about the hip (it leaves the ground without impulse)."""
    _, g = passive_optimum
    l, a, b, m, mh = 1.0, 0.5, 0.5, 5.0, 10.0
    pre_total, _, pre_stance = _momenta(g.pre_impact_state, l, a, b, m, mh)
    st, sw, dst, dsw = g.fixed_point  # after the swap: the old stance leg is the new swing leg
    hip_new = l * np.array([np.sin(st), np.cos(st)])
    _, post_swing, _ = _momenta(g.fixed_point, l, a, b, m, mh)
    # about the new stance foot (origin after the impact): recompute the post total there
    cross = lambda r, v: r[0] * v[1] - r[1] * v[0]
    e = lambda th: np.array([np.sin(th), np.cos(th)])
    de = lambda th, w: w * np.array([np.cos(th), -np.sin(th)])
    vhip = l * de(st, dst)
    about_foot = (mh * cross(hip_new, vhip) + m * cross(b * e(st), b * de(st, dst))
                  + m * cross(hip_new - a * e(sw), vhip - a * de(sw, dsw)))
    assert about_foot == pytest.approx(pre_total, rel=1e-9)
    assert post_swing == pytest.approx(pre_stance, rel=1e-9)


def test_speed_and_actuator_limit_hold(passive_optimum):
    """Level ground at 0.8 m/s with a weak hip: the step length is the closed-form chord between the
    feet, L/T is the speed, and the hip torque limit is met and reported active."""
    s = actuated_compass(hip_limit=2.0)  # unlimited, the hip would need about 3.5 N·m
    g = optimize_gait(s, params={"slope": 0.0}, speed=0.8, nodes=20, guess="interpolate", step_time=0.6)
    st, sw = g.pre_impact_state[:2]
    chord = 1.0 * (np.sin(st) - np.sin(sw))  # swing foot ahead of the stance foot on level ground
    assert g.step_length == pytest.approx(chord, rel=1e-9)
    assert g.step_length / g.step_time == pytest.approx(0.8, rel=1e-9)
    hip = g.inputs[:, g.input_names.index("hip")]
    assert np.abs(hip).max() <= 2.0 + 1e-8
    assert g.constraints["actuator_limits"]["active"] >= 1
    assert g.constraints["contact"]["max_violation"] <= 1e-8 and g.max_violation <= 1e-8


def test_hip_only_gait_has_bezier_virtual_constraints():
    """One input on two coordinates: the Bézier polynomial of the hip angle in the phase (the hip's
    progress along the slope, closed form l·sin(stance − slope)) reproduces the collocated hip angle."""
    s = actuated_compass(ankle=False)
    g = optimize_gait(s, params={"slope": SLOPE}, speed=0.8, nodes=20, bezier_degree=6)
    bz = g.bezier
    assert bz is not None and bz["outputs"] == ["-1.0*stance + 1.0*swing"]
    theta = np.sin(g.states[:, 0] - SLOPE)  # the hip's distance ahead of the stance foot, leg length 1 m
    sph = (theta - bz["phase"]["theta_plus"]) / (bz["phase"]["theta_minus"] - bz["phase"]["theta_plus"])
    y = bernstein(sph, bz["degree"]) @ np.array(bz["alpha"][0])
    assert bz["phase"]["theta_plus"] == pytest.approx(theta[0], rel=1e-12)
    err = np.abs(y - (g.states[:, 1] - g.states[:, 0])).max()
    assert err == pytest.approx(bz["fit_error"], rel=1e-6) and err <= 2e-2  # rad, of a 0.9 rad swing


def test_bernstein_basis_is_a_partition_of_unity():
    s = np.linspace(0, 1, 11)
    B = bernstein(s, 5)
    assert np.allclose(B.sum(axis=1), 1.0) and B[0, 0] == 1.0 and B[-1, -1] == 1.0


def test_bad_input_and_failure_are_typed():
    s = load("compass-gait")
    with pytest.raises(ParameterError, match="over-determined"):
        optimize_gait(s, speed=1.0, nodes=10)
    with pytest.raises(ParameterError, match="speed or step_length"):
        optimize_gait(s, speed=1.0, step_length=0.5)
    with pytest.raises(ParameterError, match="nodes"):
        optimize_gait(s, nodes=1)
    with pytest.raises(ParameterError, match="foo"):
        optimize_gait(s, objective="foo + 1")
    with pytest.raises(SolverError, match="iteration limit"):
        optimize_gait(actuated_compass(), params={"slope": 0.0}, speed=0.8, nodes=10, guess="stand", max_iter=2)


def test_hzd_gait_walks_in_closed_loop_under_its_virtual_constraints():
    """A hip-actuated compass gait designed with virtual constraints (mesh refined 20 → 60), then
    walked by the library's HZD controller with the exported Bézier α: the closed-loop step stays
    within 1e-4 of the collocated one, and Newton on the closed-loop return map (refinement)
    converges next to the optimised fixed point with residual ≤ 1e-8."""
    s = actuated_compass(ankle=False)
    g = optimize_gait(s, params={"slope": SLOPE}, speed=0.8, nodes=[20, 60], bezier_degree=6, hzd=True)
    bz = g.bezier
    assert g.max_violation <= 1e-8 and bz["fit_error"] <= 1e-6
    loop = compass_gait.build()
    m = loop.modes["compass-gait"]
    st, sw = m.q
    m.actuator("hip", on=sw - st)
    m.virtual_constraints([m.parse(o) for o in bz["outputs"]],
                          m.parse(bz["phase"]["expression"]), bz["alpha"],
                          (bz["phase"]["theta_plus"], bz["phase"]["theta_minus"]), epsilon=0.005)
    tr = simulate(loop, g.fixed_point, params={"slope": SLOPE}, steps=1, sample_dt=0.005)
    ev = tr.step_events[0]
    inside = tr.t < min(ev.t, g.step_time)
    assert np.abs(tr.x[inside] - g.state(tr.t[inside])).max() <= 1e-4
    assert np.abs(ev.x_post - g.fixed_point).max() <= 1e-5
    lc = find_fixed_point(loop, g.fixed_point, params={"slope": SLOPE})
    assert lc.residual <= 1e-8 and np.abs(lc.fixed_point - g.fixed_point).max() <= 1e-5


def _replay_error(nodes):
    """A powered compass gait on level ground (hip and ankle, 0.8 m/s, ``nodes`` intervals) and its
    open-loop replay with :meth:`Gait.input_laws`: the laws at the collocation points (N·m, largest
    difference from the optimised inputs), and how far the simulated step is from the collocated one
    (rad, rad/s; largest over the step, and after the impact)."""
    import sympy as sp

    from amble.modelling.geometry import t as time

    g = optimize_gait(actuated_compass(), params={"slope": 0.0}, speed=0.8, nodes=nodes, guess="interpolate",
                      step_time=0.6)
    replay = actuated_compass()
    m = replay.modes["compass-gait"]
    laws = g.input_laws(m)
    at_points = np.column_stack([sp.lambdify(time, laws[u], "numpy")(g.times) for u in m.inputs])
    m.control(laws)
    tr = simulate(replay, g.fixed_point, params={"slope": 0.0}, steps=1, sample_dt=0.005)
    ev = tr.step_events[0]
    inside = tr.t < min(ev.t, g.step_time)
    assert inside.sum() > 50  # a step of about 0.5 s, sampled every 5 ms
    return (np.abs(at_points - g.inputs).max() / np.abs(g.inputs).max(),
            np.abs(tr.x[inside] - g.state(tr.t[inside])).max(), np.abs(ev.x_post - g.fixed_point).max())


def test_input_laws_replay_the_gait_with_the_collocations_fourth_order_error():
    """The laws pass through the optimised inputs at every collocation point (to round-off), and
    the open-loop walk under them — amble's integrator, not the collocation — follows the
    collocated step with the error of Hermite–Simpson collocation, fourth order in the interval:
    halving the intervals (10 → 20) divides it by about 2⁴ = 16."""
    coarse, fine = _replay_error(10), _replay_error(20)
    assert coarse[0] <= 1e-12 and fine[0] <= 1e-12
    assert fine[1] <= 1e-5 and fine[2] <= 1e-5
    assert 10 < coarse[1] / fine[1] < 25 and 10 < coarse[2] / fine[2] < 25


@pytest.mark.slow
def test_open_loop_replay_of_optimised_inputs_reproduces_the_gait():
    """A powered gait on level ground (hip and ankle, 0.8 m/s, mesh 20 → 80) replayed open loop
    with the optimised inputs as laws of time: the simulated step follows the collocated one and
    returns to the fixed point to the collocation's accuracy (an open-loop law of time has no
    autonomous return map to refine by Newton, unlike the passive and HZD loops above). The fine
    mesh of the replay at 10 and 20 intervals above: its law of 80 pieces takes longer to compile."""
    g = optimize_gait(actuated_compass(), params={"slope": 0.0}, speed=0.8, nodes=[20, 80], guess="interpolate",
                      step_time=0.6)
    replay = actuated_compass()
    m = replay.modes["compass-gait"]
    m.control(g.input_laws(m))
    tr = simulate(replay, g.fixed_point, params={"slope": 0.0}, steps=1, sample_dt=0.005)
    ev = tr.step_events[0]
    inside = tr.t < min(ev.t, g.step_time)
    assert np.abs(tr.x[inside] - g.state(tr.t[inside])).max() <= 1e-4
    assert np.abs(ev.x_post - g.fixed_point).max() <= 1e-6
