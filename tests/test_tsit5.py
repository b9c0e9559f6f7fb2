"""The Tsitouras 5(4) integrator (``_c/tsit5.h``, one row of ``abi.METHODS``) against SciPy's
solve_ivp on the same compiled right-hand side: a smooth double pendulum (end state and the
samples of its free 4th-order dense output), the compass gait's and the rimless wheel's first
step (impact time and pre-impact state), the kneed biped's knee lock; its order with a fixed step;
sensitivities through the same stepper interface as DOP853's; the command line."""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import amble
from amble import HybridSystem, Model
from amble.backend.abi import CTX, HAS_SENSITIVITIES, METHODS, NEEDS_JACOBIAN
from amble.backend.kernels import compiled
from amble.cli.main import main
from amble.models import load
from amble.simulation.engine import Options, run
from amble.simulation.simulate import initial_state, parameter_vector

TOL = 1e-10  # Tsit5's rtol and atol
REF = dict(method="DOP853", rtol=1e-13, atol=1e-13)  # SciPy's reference


def _double_pendulum() -> HybridSystem:
    m = Model("t5-double-pendulum")
    a, b = m.coordinates("a b")
    m.point("p1", (sp.sin(a), -sp.cos(a)), mass=1.0)
    m.point("p2", (sp.sin(a) + sp.sin(b), -sp.cos(a) - sp.cos(b)), mass=0.5)
    m.gravity(9.81)
    return HybridSystem("t5-double-pendulum", m)


X0 = [1.2, -0.4, 0.0, 0.5]


def test_the_table_row():
    assert (2, "tsit5", False, True) in METHODS and not NEEDS_JACOBIAN["tsit5"] and HAS_SENSITIVITIES["tsit5"]


def test_a_smooth_model_and_its_dense_output_match_scipy():
    s = _double_pendulum()
    k = compiled(s)
    p = parameter_vector(k, None, s)
    tr = amble.simulate(s, X0, t_end=3.0, method="tsit5", rtol=TOL, atol=TOL, sample_dt=0.01)
    assert tr.status == "end_time"
    ref = solve_ivp(lambda t, x: k.rhs(0, t, x, p), (0.0, 3.0), X0, t_eval=tr.t, **REF)
    # the global error over 3 s of motion, a few tolerances (measured 6e-10), of the order of
    # SciPy's own 5(4) pair, RK45, at the same tolerances (2e-10); the samples between steps lie
    # on the 4th-order interpolant, a little further off (measured 3e-9)
    err = np.max(np.abs(tr.x[-1] - ref.y[:, -1]))
    rk45 = solve_ivp(lambda t, x: k.rhs(0, t, x, p), (0.0, 3.0), X0, method="RK45", rtol=TOL, atol=TOL)
    assert err < 30 * TOL and err < 10 * np.max(np.abs(rk45.y[:, -1] - ref.y[:, -1]))
    np.testing.assert_allclose(tr.x, ref.y.T, rtol=0, atol=100 * TOL)
    assert len(tr.t) == 301


def _first_event(name: str, guard: int, t_free: float = 0.05):
    """SciPy's first crossing of the mode's guard downwards after t_free (past the start, where
    walkers begin with the guard at zero, and past a swing foot's scuffing, which the guard's
    enabling condition ignores), and amble's Tsit5 run to its first event."""
    s = load(name)
    k = compiled(s)
    p = parameter_vector(k, None, s)
    mi, x0 = initial_state(s, k, None, None)
    f = lambda t, x: k.rhs(mi, t, x, p)  # noqa: E731
    x1 = solve_ivp(f, (0.0, t_free), x0, **REF).y[:, -1]
    ev = lambda t, x: k.guards(mi, t, x, p)[guard]  # noqa: E731
    ev.terminal, ev.direction = True, -1
    sol = solve_ivp(f, (t_free, 5.0), x1, events=ev, **REF)
    tr = amble.simulate(s, x0, steps=1, method="tsit5", rtol=TOL, atol=TOL, samples=False)
    return sol.t_events[0][0], sol.y_events[0][0], tr.events[0]


@pytest.mark.parametrize("name, t_free", [("compass-gait", 0.5), ("rimless-wheel", 0.05)])
def test_a_walkers_first_impact_matches_scipy(name, t_free):
    t_ref, x_ref, e = _first_event(name, 0, t_free)
    assert e.name == "heel_strike"
    assert e.t == pytest.approx(t_ref, abs=10 * TOL)  # measured: 1e-11
    np.testing.assert_allclose(e.x_pre, x_ref, rtol=0, atol=20 * TOL)


def test_the_kneed_bipeds_knee_lock_matches_scipy():
    t_ref, x_ref, e = _first_event("kneed-biped", 0)
    assert e.name == "knee_lock"
    assert e.t == pytest.approx(t_ref, abs=10 * TOL)
    np.testing.assert_allclose(e.x_pre, x_ref, rtol=0, atol=20 * TOL)  # measured: 3e-10


def test_the_error_falls_with_the_fifth_power_of_a_fixed_step():
    s = _double_pendulum()
    k = compiled(s)
    p = parameter_vector(k, None, s)
    x0 = np.array(X0)
    ref = solve_ivp(lambda t, x: k.rhs(0, t, x, p), (0.0, 1.0), x0, **REF).y[:, -1]
    errs = []
    for h in (0.02, 0.01, 0.005):  # in the asymptotic range (at 0.04 the ratio is still 14)
        # tolerances that accept every step: the step is max_step throughout
        r = run(k, p, 0, x0, t_end=1.0, opts=Options(rtol=0.5, atol=0.5, max_step=h, method="tsit5"))
        assert r.status == "end_time" and r.ctx[CTX["ISTEPS"]] == round(1.0 / h)  # no step rejected
        errs.append(np.max(np.abs(r.x - ref)))
    for coarse, fine in zip(errs, errs[1:]):
        assert 2**5 * 0.7 < coarse / fine < 2**5 * 1.4  # measured: 34 and 36


def test_sensitivities_ride_on_the_tsit5_stages():
    s = load("compass-gait")
    k = compiled(s, derivatives=True)
    p = parameter_vector(k, None, s)
    _, x0 = initial_state(s, k, None, None)
    got = {}
    for m in ("dop853", "tsit5"):
        r = run(k, p, 0, x0, steps=1, opts=Options(rtol=1e-11, atol=1e-11, method=m), sensitivities=True)
        assert r.status == "completed"
        got[m] = r.sensitivity
    np.testing.assert_allclose(got["tsit5"].dx_dx0, got["dop853"].dx_dx0, rtol=0, atol=1e-7)
    np.testing.assert_allclose(got["tsit5"].dx_dp, got["dop853"].dx_dp, rtol=0, atol=1e-7)


def test_the_command_line_simulates_with_tsit5(capsys, tmp_path):
    out = tmp_path / "cg.csv"
    assert main(["simulate", "compass-gait", "--method", "tsit5", "--steps", "2", "--out", str(out)]) == 0
    assert out.stat().st_size > 0
    capsys.readouterr()
