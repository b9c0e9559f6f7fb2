"""Gaits of walkers whose stance feet are modes: the period is the cycle of modes (left stance →
right stance), each step exported from its own mode with the derived impact into the next.

Truth: the passive compass gait written as two modes is Goswami's gait (an independent SciPy
integration of his equations, tests/oracles/compass_gait.py) — collocation reproduces it to its
discretisation error; RABBIT loaded from its URDF as two stance modes has the same optimal gait as
the same robot written as one mode whose footfall swaps the legs by hand (two formulations of one
mechanical problem: the optimum does not depend on how the legs are named)."""

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("casadi")

sys.path.insert(0, str(Path(__file__).parents[1]))

from two_mode_walkers import compass_two_modes, compass_two_modes_hzd, rabbit_stance, rabbit_two_modes  # noqa: E402

from amble import closed_loop_stability, simulate, walker  # noqa: E402
from amble.analysis.gait_optimisation import optimize_gait  # noqa: E402
from amble.errors import ModelError, ParameterError  # noqa: E402
from amble.models import load  # noqa: E402


def test_a_passive_two_mode_compass_gait_is_goswamis_gait():
    from oracles import compass_gait as cg

    g = optimize_gait(compass_two_modes(), nodes=30)  # no inputs: the only step is the passive one
    assert g.modes == ["left", "right"] and len(g.steps) == 2
    assert g.max_violation <= 1e-10
    x, _ = cg.fixed_point(0.05)
    truth = np.array([-x[1], -x[0], -x[3], -x[2]])  # Goswami's (th_ns, th_s) = −(swing, stance)
    for step in g.steps:  # both stances take the same step
        np.testing.assert_allclose(step.fixed_point, truth, rtol=0, atol=2e-6)
    # the step time against the oracle's own integration from its fixed point
    _, T = cg.step(x, 0.05)
    assert abs(g.step_time - T) <= 1e-6
    assert abs(g.steps[1].step_time - T) <= 1e-6


def test_a_period_of_a_two_mode_walker_is_a_whole_cycle_of_modes():
    with pytest.raises(ParameterError, match="multiple of 2 footfalls"):
        optimize_gait(compass_two_modes(), nodes=10, steps=1)
    with pytest.raises(ModelError, match="one domain"):
        optimize_gait(load("kneed-biped"), nodes=10)  # its step passes through the knee lock


def _one_mode_rabbit(start):
    m = rabbit_stance("left")
    q = {str(s): s for s in m.q}
    swap = {q["left_knee"]: q["right_knee"], q["left_hip"]: q["right_hip"], q["right_hip"]: q["left_hip"],
            q["right_knee"]: q["left_knee"],
            q["stance"]: q["stance"] - q["left_knee"] - q["left_hip"] + q["right_hip"] + q["right_knee"]}
    return walker(m, foot="right_foot", hip="torso", slope=0.0, relabel=swap, start=start)


def test_rabbit_as_two_stance_modes_has_the_optimum_of_rabbit_with_legs_swapped_by_hand():
    two = rabbit_two_modes()
    names = [str(q) for q in two.modes["left"].q]
    posture = np.zeros(5)
    posture[[names.index("stance"), names.index("left_hip"), names.index("right_hip")]] = -0.25, 0.25, -0.25
    start = list(np.r_[posture, np.zeros(5)])
    two.default_start["left"] = start
    opts = dict(nodes=12, speed=0.8, guess="interpolate", step_time=0.5)
    a = optimize_gait(two, **opts)
    b = optimize_gait(_one_mode_rabbit(start), steps=2, **opts)
    assert a.solver["status"] == b.solver["status"] == "Solve_Succeeded"
    assert a.max_violation <= 1e-9 and b.max_violation <= 1e-9
    assert abs(a.objective - b.objective) <= 1e-8 * abs(b.objective)
    np.testing.assert_allclose(a.fixed_point, b.fixed_point, rtol=0, atol=1e-8)
    np.testing.assert_allclose([s.step_time for s in a.steps], [s.step_time for s in b.steps], rtol=1e-8)
    assert a.speed == pytest.approx(0.8, rel=1e-9)


@pytest.mark.parametrize("bound", [None, 0.3])
def test_a_two_mode_hzd_gait_walks_in_closed_loop_with_the_restricted_maps_multiplier(bound):
    w = compass_two_modes_hzd()
    g = optimize_gait(w, nodes=20, speed=0.6, guess="interpolate", step_time=0.7, max_multiplier=bound)
    assert g.max_violation <= 1e-9 and g.modes == ["left", "right"]
    assert g.steps[0].bezier["alpha"] == g.steps[1].bezier["alpha"]  # one controller for both stances
    params = {**g.params, **g.bezier["params"]}
    walk = simulate(w, x0=g.fixed_point, params=params, steps=20, t_end=60.0)
    assert walk.status == "completed" and len(walk.step_events) == 20
    assert [e.source for e in walk.step_events[:2]] == ["left", "right"]
    mu = g.stability["restricted_multiplier"]
    if bound is None:
        assert 0.3 < mu < 1.0  # the free optimum is stable, and above the bound tried next
    else:
        assert mu == pytest.approx(bound, rel=1e-8)  # the bound binds
    loop = closed_loop_stability(w, g)
    assert loop["residual"] <= 1e-10 and loop["fixed_point_distance"] <= 2e-4  # the collocation's error
    assert loop["spectral_radius"] == pytest.approx(mu, rel=1e-8)
    assert abs(complex(*loop["multipliers"][1])) <= 1e-9  # transverse to the zero dynamics: ε small


def test_each_stance_mode_may_keep_its_own_controller():
    """Coefficients named per mode are unknowns per step: a relaxation of one shared set, so its
    optimum is at most the shared design's (at a speed only the pair's pace is held: the pair's
    optimum is asymmetric, each step with its own polynomial), and the compiled controller walks it."""
    shared = optimize_gait(compass_two_modes_hzd(), nodes=20, speed=0.6, guess="interpolate", step_time=0.7)
    w = compass_two_modes_hzd(shared=False)
    own = optimize_gait(w, nodes=20, speed=0.6, guess="interpolate", step_time=0.7)
    p = own.bezier["params"]
    assert {"left_alpha_0_0", "right_alpha_0_0", "left_phase_start", "right_phase_end"} <= set(p)
    assert own.objective <= shared.objective * (1 + 1e-9)
    assert abs(p["left_alpha_0_2"] - p["right_alpha_0_2"]) > 1e-3  # two polynomials, not one
    assert own.steps[0].bezier["alpha"] != own.steps[1].bezier["alpha"]
    walk = simulate(w, x0=own.fixed_point, params={**own.params, **p}, steps=20, t_end=60.0)
    assert walk.status == "completed" and len(walk.step_events) == 20
    loop = closed_loop_stability(w, own)
    assert loop["spectral_radius"] == pytest.approx(own.stability["restricted_multiplier"], rel=1e-8)


def test_a_solver_stopped_at_a_feasible_point_hands_back_its_gait(monkeypatch):
    """IPOPT stopped where every constraint holds but optimality is not certified (the iteration
    limit on a 3D biped): the error carries the periodic gait of its last iterate, read back like
    a solution. The stop is made here by letting the solver finish and reporting it as stopped."""
    import amble.analysis.gait_ipopt as gi
    from amble.errors import SolverError

    real = gi._solve_nlp

    def stopped(*args, **kw):
        out = real(*args, **kw)
        err = SolverError("gait optimisation failed after 26 iterations: iteration limit reached; every "
                          "constraint holds at the last iterate (the optimality conditions do not)")
        err.feasible = out
        raise err

    monkeypatch.setattr(gi, "_solve_nlp", stopped)
    with pytest.raises(SolverError, match="every constraint holds") as info:
        optimize_gait(compass_two_modes_hzd(), nodes=20, speed=0.6, guess="interpolate", step_time=0.7)
    g = info.value.gait
    assert g is not None and g.modes == ["left", "right"] and g.max_violation <= 1e-9
    assert g.speed == pytest.approx(0.6, rel=1e-9)
