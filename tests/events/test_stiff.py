"""The implicit integrator (Radau IIA) on stiff systems: a closed form, the step counts that
make the difference, event location shared with DOP853, and the hint a stiff explicit run gives."""

import math

import numpy as np
import pytest
import sympy as sp

from amble import HybridSystem, Model, Options, simulate
from amble.backend.abi import CTX
from amble.backend.kernels import build
from amble.errors import StateError
from amble.models import load
from amble.simulation.engine import run
from amble.simulation.simulate import parameter_vector


def _overdamped() -> HybridSystem:
    """m ẍ + c ẋ + k x = 0 with c = k = 1e4, m = 1: eigenvalues ≈ −1 and −9999 (stiff)."""
    m = Model("stiff-damper")
    (x,) = m.coordinates(["x"])
    k, c = m.parameters(k=1e4, c=1e4)
    m.point("mass", sp.Matrix([x, 0]), mass=1.0)
    m.add_potential(k * x**2 / 2)
    m.force([-c * m.dot(x)])
    return HybridSystem("stiff-damper", m)


def _closed_form(t: float, x0: float, v0: float, k: float = 1e4, c: float = 1e4) -> float:
    disc = math.sqrt(c * c - 4 * k)
    l1, l2 = (-c + disc) / 2, (-c - disc) / 2
    b = (v0 - l1 * x0) / (l2 - l1)
    return (x0 - b) * math.exp(l1 * t) + b * math.exp(l2 * t)


def test_radau_matches_the_closed_form_in_few_steps():
    s = _overdamped()
    k = build(s, derivatives=True)
    p = parameter_vector(k, None, s)
    x0 = np.array([1.0, 0.0])
    steps = {}
    for method in ("radau", "dop853"):
        r = run(k, p, 0, x0, t_end=2.0, opts=Options(rtol=1e-9, atol=1e-12, method=method))
        assert r.status == "end_time"
        assert r.x[0] == pytest.approx(_closed_form(2.0, 1.0, 0.0), rel=1e-6)
        steps[method] = r.ctx[CTX["ISTEPS"]]
    # stability, not accuracy, bounds the explicit steps (|λ| h ≲ 6 for DOP853)
    assert steps["dop853"] > 2000 and steps["radau"] < steps["dop853"] / 5


def test_events_are_located_alike_by_both_integrators():
    s = load("compass-gait")
    times = []
    for method in ("dop853", "radau"):
        tr = simulate(s, s.fixed_point_guess, steps=5, rtol=1e-11, atol=1e-11, method=method, samples=False)
        assert tr.status == "completed"
        times.append(np.array([e.t for e in tr.events]))
    np.testing.assert_allclose(times[0], times[1], atol=1e-8)


def test_a_stiff_controller_runs_with_radau_and_agrees_on_a_milder_gain():
    s = load("humanoid-2d")
    x0 = s.fixed_point_guess
    tr = simulate(s, x0, params={"kT": 1e12, "kv": 1e10}, steps=2, method="radau", samples=False)
    assert tr.status == "completed"
    ends = [simulate(s, x0, params={"kT": 1e6, "kv": 1e4}, steps=2, rtol=1e-11, atol=1e-11, method=m,
                     samples=False) for m in ("dop853", "radau")]
    np.testing.assert_allclose(ends[0].final_post_impact_state, ends[1].final_post_impact_state, atol=1e-8)
    assert ends[0].events[-1].t == pytest.approx(ends[1].events[-1].t, abs=1e-9)


def test_a_stiff_explicit_run_suggests_the_implicit_integrator():
    s = load("humanoid-2d")
    tr = simulate(s, s.fixed_point_guess, params={"kT": 1e12, "kv": 1e10}, steps=2, samples=False,
                  options=Options(max_integrator_steps=20_000, max_step_time=5))
    assert tr.status == "max_integrator_steps" and "method='radau'" in tr.message


def test_sensitivities_need_the_explicit_integrator():
    s = load("compass-gait")
    k = build(s, derivatives=True)
    with pytest.raises(StateError, match="sensitivities need method='dop853'"):
        run(k, parameter_vector(k, None, s), 0, np.asarray(s.fixed_point_guess, float), steps=1,
            opts=Options(method="radau"), sensitivities=True)
    with pytest.raises(StateError, match="method must be one of"):
        Options(method="rk4")
