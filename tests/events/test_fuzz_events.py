"""Random piecewise forces and random guards, each run under a step budget that none exceeds:
every case ends with a status of its own (end_time, sliding, a terminal), never by exhausting
the budget. Where the force depends on θ alone it has a potential, and the energy computed here
from the state (not by amble) is conserved along the whole run; with Coulomb friction added it
never increases."""

import re

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from systems import pendulum

import amble
from amble import Guard, HybridSystem, Options

_BUDGET = Options(max_steps_between_events=20_000, max_integrator_steps=50_000)
_SYS: list[HybridSystem] = []


def _system() -> HybridSystem:
    """θ̈ = −g sin θ + τ, τ = −k₁ if θ + c θ̇ > d, else k₂ (+ −f sign(θ̇)); a terminal guard θ = A."""
    if not _SYS:
        def torque(th, thd, m):
            k1, k2, c, d, f = m.parameters(k1=1.0, k2=1.0, c=0.5, d=0.0, f=0.0)
            return sp.Piecewise((-k1, th + c * thd > d), (k2, True)) - f * sp.sign(thd)

        m, th = pendulum("ev-fuzz", torque)
        (a,) = m.parameters(A=2.0)
        s = HybridSystem("ev-fuzz", m)
        s.terminal("past_A", "ev-fuzz", Guard(a - th, -1), status="past_A")
        _SYS.append(s)
    return _SYS[0]


def _energy(tr, k1: float, k2: float, d: float, g: float = 9.81) -> np.ndarray:
    """½θ̇² + g(1 − cos θ) + U(θ) per row, with U the potential of the switching torque when the
    switch is θ = d (c = 0): τ = −k₁ above d, +k₂ below, so U = k₁(θ − d) above, −k₂(θ − d) below
    (continuous at d, U′ = −τ)."""
    th, thd = tr.column("theta"), tr.column("theta_dot")
    u = np.where(th > d, k1 * (th - d), -k2 * (th - d))
    return 0.5 * thd**2 + g * (1.0 - np.cos(th)) + u


# The energy tolerance, relative to 1 + |E(0)|. DOP853 at its default rtol = atol = 1e-10 keeps
# each step's local error at ~1e-10 per unit of state; these runs take fewer than 1000 steps
# (measured: < 400 for the conservative ones) and |∂E/∂x| ≤ g + max(k₁, k₂) + |θ̇| stays within
# ~10 (1 + |E|), so the drift is bounded by 1000 · 10 · 1e-10 = 1e-6 (1 + |E|); observed ~3e-9.
# A lost or wrong-signed torque, or a kick at the switch, changes E by O(k |θ − d|) ≫ this.
_E_TOL = 1e-6


def _check_energy(tr, k1: float, k2: float, c: float, d: float, f: float) -> None:
    if c != 0.0:
        return  # the switch θ + cθ̇ = d makes the torque depend on θ̇: it has no potential
    e = _energy(tr, k1, k2, d)
    tol = _E_TOL * (1.0 + abs(e[0]))
    if f == 0.0:
        assert np.max(np.abs(e - e[0])) < tol, np.max(np.abs(e - e[0]))
    elif e.size > 1:  # dE/dt = −f |θ̇| ≤ 0, sticking included (θ̇ = 0, θ fixed)
        assert np.max(np.diff(e)) < tol, np.max(np.diff(e))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    k1=st.floats(0.0, 30.0), k2=st.floats(0.0, 30.0), c=st.one_of(st.just(0.0), st.floats(-1.0, 1.0)),
    d=st.floats(-0.5, 0.5), f=st.sampled_from([0.0, 0.0, 2.0, 8.0]), a=st.floats(0.05, 3.0),
    th0=st.floats(-1.0, 1.0), thd0=st.floats(-3.0, 3.0),
)
def test_random_switching_forces_and_guards_end_within_the_budget(k1, k2, c, d, f, a, th0, thd0):
    params = {"k1": k1, "k2": k2, "c": c, "d": d, "f": f, "A": a}
    tr = amble.simulate(_system(), [th0, thd0], params=params, t_end=5.0, options=_BUDGET)
    # c < 0 tilts the switching line so that the flow leaves it on both sides near θ̇ = 0: a
    # self-sustained oscillation about it, amplitude ∝ |c| (test below), which no step budget
    # outlasts; and a switch that pushes back from both sides (k₁, k₂ > 0) keeps a swing about it
    # as small as it started (θ₀ = d, θ̇₀ = 1.5e-3: 5.6e-7 rad, a crossing every 0.75 ms) for
    # longer than the budget (the conservative test below). Such a run must say so, near the
    # switch, and never blame stiffness
    if tr.status == "stalled" and (c < 0 or abs(tr.final_state[0] + c * tr.final_state[1] - d) < 1e-3):
        assert "chatters about the switch" in tr.message and "radau" not in tr.message, tr.message
    else:
        assert tr.status in ("end_time", "sliding", "past_A", "zeno"), tr.message
    if tr.status == "end_time":
        assert tr.t[-1] == pytest.approx(5.0, abs=1e-12)
    _check_energy(tr, k1, k2, c, d, f)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    k1=st.floats(0.0, 30.0), k2=st.floats(0.0, 30.0), d=st.floats(-0.5, 0.5), a=st.floats(0.05, 3.0),
    th0=st.floats(-1.0, 1.0), thd0=st.floats(-3.0, 3.0),
)
def test_random_conservative_switching_forces_conserve_energy(k1, k2, d, a, th0, thd0):
    # τ = −k₁ above θ = d, +k₂ below, no friction: a force with a potential, so
    # ½θ̇² + g(1 − cos θ) + U(θ) is constant through every crossing of the switch, including
    # where the net force at the switch vanishes on one side (k₁ = 0 or k₂ = 0 with d = 0: the
    # flow there tangent to the switch, tested by itself below)
    params = {"k1": k1, "k2": k2, "c": 0.0, "d": d, "f": 0.0, "A": a}
    tr = amble.simulate(_system(), [th0, thd0], params=params, t_end=5.0, options=_BUDGET)
    # a start just below a switch that pushes back from both sides (k₁, k₂ > 0) oscillates about
    # it with an amplitude of |θ₀ − d|, crossing it every few ms: a tiny enough one outlasts the
    # step budget, and must say that it chatters about the switch
    if tr.status == "stalled":
        assert "chatters about the switch" in tr.message and abs(tr.final_state[0] - d) < 1e-3, tr.message
    else:
        assert tr.status in ("end_time", "past_A", "zeno", "sliding"), tr.message
    _check_energy(tr, k1, k2, 0.0, d, 0.0)


def test_a_start_at_rest_on_a_switch_where_the_force_above_vanishes_stays_there():
    # τ = +1 below θ = 0, nothing above, no friction. At the origin the flow below, (θ̇, θ̈) =
    # (0, 1 − g sin θ), is tangent to the switch and curves up into θ > 0 (g̈ = 1); the flow above,
    # (0, −g sin θ), is at rest there and curves down just above it (g̈ = −g sin θ < 0): both point
    # into the other side. The energy ½θ̇² + g(1 − cos θ) + U(θ) (U = 0 above, −θ below) is ≥ 0,
    # zero only at the origin, and constant along every Filippov solution, so the only one from
    # the origin stays there: at rest on the switch, which amble reports as sliding on θ at once
    # (it used to let the steps straddle the switch, then jump to θ ≈ 1 rad: 4.4 J)
    params = {"k1": 0.0, "k2": 1.0, "c": 0.0, "d": 0.0, "f": 0.0, "A": 2.0}
    tr = amble.simulate(_system(), [0.0, 0.0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status == "sliding" and tr.t[-1] == 0.0, tr.message
    surface = re.search(r"switching surface \d+ \((.*)\) at t", tr.message)
    assert surface and "theta" in surface[1] and surface[1] != "theta_dot", tr.message  # θ = d, not θ̇ = 0
    assert tr.final_state[0] == 0.0 and tr.final_state[1] == 0.0


def test_a_pendulum_hanging_at_rest_on_switches_without_force_stays_there_to_the_end():
    # k₁ = k₂ = f = 0: the switches θ = 0 and θ̇ = 0 change no force, and the hanging pendulum is
    # an equilibrium on both; just off them the flow rotates about it (curving back into θ̇ = 0
    # from both sides), which must not be taken for sliding: the run lasts to its end, at rest
    params = {"k1": 0.0, "k2": 0.0, "c": 0.0, "d": 0.0, "f": 0.0, "A": 2.0}
    tr = amble.simulate(_system(), [0.0, 0.0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status == "end_time", tr.message
    assert np.all(tr.column("theta") == 0.0) and np.all(tr.column("theta_dot") == 0.0)


def test_a_start_at_rest_on_a_switch_whose_flows_both_go_up_sets_off_upwards():
    # τ = +1 above θ = 0 (k₁ = −1), nothing below. At θ = 0 the Piecewise takes the branch below,
    # whose flow (θ̇, −g sin θ) is at rest there but curves up just below it (g̈ = −g sin θ > 0);
    # the flow above, (0, 1 − g sin θ), moves up: both go into θ > 0, and the run sets off upwards.
    # (Resting at θ = 0 is a Filippov solution too — the field below vanishes there — but one
    # that no perturbation, however small, stays on; the run used to rest there throughout.)
    # E = ½θ̇² + g(1 − cos θ) − θ is 0, so the swing rises to the root θ_max of g(1 − cos θ) = θ
    # and comes back after about 2π/√g = 2.0 s (the harmonic θ̈ ≈ 1 − gθ): run to 1.5 s, past the
    # top (about π/√g = 1.0 s) and before the return
    from scipy.optimize import brentq

    g = 9.81
    th_max = brentq(lambda th: g * (1.0 - np.cos(th)) - th, 0.1, 0.5)
    params = {"k1": -1.0, "k2": 0.0, "c": 0.0, "d": 0.0, "f": 0.0, "A": 2.0}
    tr = amble.simulate(_system(), [0.0, 0.0], params=params, t_end=1.5, sample_dt=1e-3, options=_BUDGET)
    assert tr.status == "end_time", tr.message
    th = tr.column("theta")
    e = _energy(tr, -1.0, 0.0, 0.0)
    assert np.max(np.abs(e)) < 1e-8, np.max(np.abs(e))
    # the grid misses the top by ≤ ½ |θ̈| (0.5 ms)² ≈ 1.3e-7 rad (θ̈ = 1 − g sin θ_max ≈ −1 there)
    assert th_max - 2e-7 < np.max(th) < th_max + 1e-9 and np.min(th) > -1e-9


@pytest.mark.parametrize("thd0", [-1e-9, 1e-9, -1e-6])
def test_a_start_on_a_switch_where_the_force_above_vanishes_keeps_its_energy(thd0):
    # the same switch, started on it with a small θ̇₀: E = θ̇₀²/2 is conserved, so the pendulum
    # swings above the switch to √(2E/g) = |θ̇₀|/√g and dips below it to −E at most, crossing it
    # every half period π/√g. The steps near the switch, where the flow is almost tangent to it,
    # used to end a rounding unit across it with the force of the far side in their dense output:
    # a jump from 1e-10 rad to 3e-3 rad within one sample, and swings of 4.4 J
    params = {"k1": 0.0, "k2": 1.0, "c": 0.0, "d": 0.0, "f": 0.0, "A": 2.0}
    tr = amble.simulate(_system(), [0.0, thd0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status in ("end_time", "sliding", "zeno"), tr.message
    _check_energy(tr, 0.0, 1.0, 0.0, 0.0, 0.0)
    # within the state tolerance (atol = 1e-10) of the closed-form bounds
    th = tr.column("theta")
    assert np.max(th) < abs(thd0) / np.sqrt(9.81) + 1e-9 and np.min(th) > -thd0**2 / 2 - 1e-9


def test_a_switch_that_repels_on_both_sides_chatters_and_says_so():
    # τ = −3 above θ − 1e-5 θ̇ = 0, +3 below, friction 2 sign(θ̇): near rest the line θ = cθ̇ with c < 0
    # sends the flow away on both sides, so the pendulum settles into a tiny oscillation about
    # θ = 0 (an independent SciPy event integration grows from 1e-12 rad to a steady ≈ 7.5e-10 rad,
    # period ≈ 1.2e-4 s): it exhausts the budget, reported as chatter, at a state of that size
    params = {"k1": 3.0, "k2": 3.0, "c": -1e-5, "d": 0.0, "f": 2.0, "A": 2.0}
    tr = amble.simulate(_system(), [0.3, 0.0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status == "stalled" and "chatters about the switch" in tr.message, tr.message
    assert "looks stiff" not in tr.message and "radau" not in tr.message
    assert abs(tr.final_state[0]) < 1e-7 and abs(tr.final_state[1]) < 1e-2


def test_a_start_at_the_kink_equilibrium_slides_there_at_once():
    # θ = d, θ̇ = 0 with the torque pointing back on both sides: both flows are tangent to the
    # surface (ġ = 0) and curve back into it (g̈ = −g sin d − 5 = −0.297 above, −g sin d = 4.70
    # below), so the Filippov solution stays at rest at the kink: sliding, from the start (it
    # used to chatter about the kink until the crossings accumulated into a zeno end)
    params = {"k1": 5.0, "k2": 0.0, "c": 0.0, "d": -0.5, "f": 0.0, "A": 1.0}
    tr = amble.simulate(_system(), [-0.5, 0.0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status == "sliding" and tr.t[-1] == 0.0, tr.message
    assert tuple(tr.final_state) == (-0.5, 0.0)


def test_friction_damped_oscillation_about_a_kink_ends_as_zeno_at_rest():
    # τ = 5 below θ = 0.25, 0 above, and friction 2 sign(θ̇): the swings about the kink shrink to
    # nothing in finite time (period ∝ √amplitude): a Zeno accumulation, at rest at θ = 0.25
    params = {"k1": 0.0, "k2": 5.0, "c": 0.0, "d": 0.25, "f": 2.0, "A": 1.0}
    tr = amble.simulate(_system(), [0.0, 0.0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status == "zeno", tr.message
    assert abs(tr.final_state[0] - 0.25) < 1e-9 and abs(tr.final_state[1]) < 1e-6


def test_coulomb_friction_started_at_rest_sticks_at_once():
    # θ̇ = 0 exactly on the surface of sign(θ̇), |g sin θ| < 6: static friction holds
    from systems import coulomb_pendulum

    tr = amble.simulate(coulomb_pendulum("ev-coulomb"), [0.3, 0.0], t_end=5.0, options=_BUDGET)
    assert tr.status == "sliding" and tr.t[-1] == 0.0, tr.message


def test_marginal_coulomb_sticking_is_detected_as_sliding():
    # gravity 7.8 against friction 8: steps straddling θ̇ = 0 end on the side they started, the
    # crossing itself is never seen; the approach to the surface is tested instead
    params = {"k1": 0.0, "k2": 0.375, "c": 0.0, "d": 0.0, "f": 8.0, "A": 1.0}
    tr = amble.simulate(_system(), [-0.625, -3.0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status == "sliding", tr.message
    th, thd = tr.final_state
    assert abs(thd) < 1e-6
    assert 9.81 * abs(__import__("math").sin(th)) + 0.375 < 8.0  # static friction can hold it there


def _accumulation_time(k2: float, d: float, f: float, g: float = 9.81) -> float:
    """The time the swings of the kink test come to rest, from SciPy: from rest below the kink
    the motion alternates crossing θ = d and turning (θ̇ = 0), each segment one smooth branch
    integrated by solve_ivp to its single event; the shrinking cycles (4 events) are summed as a
    geometric series once a cycle is shorter than 1e-5 s."""
    import numpy as np
    from scipy.integrate import solve_ivp

    t, x, above, up, times = 0.0, np.array([0.0, 0.0]), False, True, []
    while not (len(times) > 8 and times[-1] - times[-5] < 1e-5):
        tau = (0.0 if above else k2) - f * (1.0 if up else -1.0)
        kink = len(times) % 2 == 0
        event = (lambda _t, y: y[0] - d) if kink else (lambda _t, y: y[1])
        event.terminal = True
        sol = solve_ivp(lambda _t, y, tau=tau: [y[1], -g * np.sin(y[0]) + tau], (t, 10.0), x, method="DOP853",
                        rtol=1e-13, atol=1e-15, events=event)
        t, x = sol.t_events[0][0], sol.y_events[0][0]
        above, up = (not above, up) if kink else (above, not up)
        times.append(t)
    r = (times[-1] - times[-5]) / (times[-5] - times[-9])
    return times[-1] + (times[-1] - times[-5]) * r / (1.0 - r)


@pytest.mark.parametrize("k2, d", [(25.0, 0.2109375), (5.0, 0.206)])
def test_swings_shrinking_onto_a_kink_with_almost_balanced_gravity_end_as_zeno_at_rest(k2, d):
    # τ = k2 below θ = d, 0 above, friction 2 sign(θ̇): above the kink gravity 9.81 sin d = 2.05
    # (2.007) barely beats friction, so each swing comes back down onto θ = d at a crawl (θ̇ ~ 5e-8
    # one rounding unit above it). That approach used to stall: ~4000 steps of 2.5e-10 s each,
    # which spread the crossings beyond zeno_dt and spent the step budget ("stalled ... stiff").
    params = {"k1": 0.0, "k2": k2, "c": 0.0, "d": d, "f": 2.0, "A": 1.0}
    tr = amble.simulate(_system(), [0.0, 0.0], params=params, t_end=5.0, options=_BUDGET)
    assert tr.status == "zeno", tr.message
    # Zeno is declared when 5 events come less than zeno_dt apart: they span < 4 zeno_dt and
    # include two turns (θ̇ = 0) and two kink crossings (θ = d), so with |θ̈| ≤ k2 + g + f the
    # state is within a (4 zeno_dt) of rest and a (4 zeno_dt)² of the kink
    a, span = k2 + 9.81 + 2.0, 4 * _BUDGET.zeno_dt
    th, thd = tr.final_state
    assert abs(thd) < a * span and abs(th - d) < a * span**2
    # and it ends where the swings accumulate: before it by the cycles still to come (a geometric
    # tail of the last cycle < 4 zeno_dt, ratio ~0.1: < 0.5 µs), shifted either way by state
    # errors of rounding size on the last crawls (δθ ~ 1e-15 above the kink takes
    # √(2 δθ / (g sin d − f)) ≈ 0.2 µs to come down); the stall ended 9 µs after it
    t_rest = _accumulation_time(k2, d, 2.0)
    assert abs(t_rest - tr.t[-1]) < 0.25 * span, (t_rest, tr.t[-1])
