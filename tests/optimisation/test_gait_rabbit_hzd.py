"""The library's RABBIT (``rabbit``: five links, four joint torques, HZD virtual constraints whose
Bézier coefficients are parameters) — a 0.8 m/s gait designed by optimisation with the model's
own virtual constraints, then walked by the model's compiled HZD controller with the exported
coefficients.

Truth the checks use, independent of the collocation: the model's own symbolic outputs
``y = h₀(q) − h_d(θ(q), α)`` (``Model.virtual``, evaluated by SymPy, not by the CasADi export)
must vanish on the gait with the exported parameters; the closed loop is amble's compiled
simulator and Newton on its exact return map.
"""

import numpy as np
import pytest
import sympy as sp

pytest.importorskip("casadi")

from amble.analysis.gait_optimisation import optimize_gait  # noqa: E402
from amble.models import rabbit  # noqa: E402

SPEED = 0.8


def _outputs_on_gait(system, gait):
    """The model's outputs ``y`` and rates ``ẏ`` (rad, rad/s) at the gait's mesh points, from the
    model's sympy expressions with the exported parameters."""
    m = system.modes[system.mode_names[0]]
    vc = m.virtual
    vals = dict(system.parameters)
    vals.update(gait.bezier["params"])
    sub = {p: vals[str(p)] for p in m.params}
    y = vc.y.xreplace(sub)
    yd = (y.jacobian(sp.Matrix(m.q)) * sp.Matrix(m.qd))
    f = sp.lambdify([*m.q, *m.qd], [list(y), list(yd)], "numpy")
    mesh = gait.states[::2]
    return np.array([np.concatenate([np.ravel(a) for a in f(*x)]) for x in mesh])


@pytest.fixture(scope="module")
def coarse_gait():
    """Coarse mesh (cheap), from the default start of a model under feedback — standing still in
    its posture, nothing moving."""
    s = rabbit.build()
    return s, optimize_gait(s, speed=SPEED, nodes=10)  # guess "stand" and hzd=True: the defaults for this model


def test_rabbit_hzd_gait_at_0_8_m_per_s_from_standing_still_satisfies_the_models_virtual_constraints(coarse_gait):
    """The coarse gait from standing still is feasible to 1e-8, walks at 0.8 m/s, and with the exported
    ``alpha``/``phase_start``/``phase_end`` the model's own virtual constraints hold at the mesh
    points; the first two Bézier columns are the hybrid-invariant ones (Westervelt et al. 2007,
    Thm. 6.5: ``α₀`` of output i is ``α_M`` of the output it is relabelled to)."""
    s, g = coarse_gait
    assert g.solver["iterations_total"] > g.solver["iterations"]  # a feasibility solve came first
    assert g.max_violation <= 1e-8
    assert all(r["max_violation"] <= 1e-8 for r in g.constraints.values())
    assert g.speed == pytest.approx(SPEED, rel=1e-9)
    assert g.constraints["contact"]["max_violation"] <= 1e-8
    assert np.abs(g.inputs).max() <= 150.0 + 1e-8
    assert np.abs(g.states[:, g.state_names.index("torso")]).max() < 0.5  # upright, not a hanging torso
    bz = g.bezier
    assert bz["phase"]["expression"] == str(s.modes["rabbit"].virtual.phase)
    assert len(bz["params"]) == 4 * 6 + 2
    assert np.abs(_outputs_on_gait(s, g)).max() <= 1e-8
    # the relabelling swaps stance and swing (rows 0 ↔ 1, 2 ↔ 3): the post-impact pose is the
    # pre-impact pose swapped, so each output starts where its relabelled partner ends
    a = np.array(bz["alpha"])
    assert np.abs(a[[1, 0, 3, 2], -1] - a[:, 0]).max() <= 1e-8


def test_rabbit_hzd_coarse_gait_walks_in_closed_loop(coarse_gait):
    """The coarse gait (10 intervals) walked by the model's compiled HZD controller with the exported
    parameters: the step ends at the collocated step time and state, to the accuracy of so coarse a
    mesh (6e-5 rad/s at the impact, 3e-6 with 20 intervals), and Newton on the closed-loop
    return map finds a stable gait next to the optimised fixed point."""
    from amble import simulate
    from amble.analysis.poincare import find_fixed_point

    s, g = coarse_gait
    P = g.bezier["params"]
    walk = simulate(s, g.fixed_point, params=P, steps=1, sample_dt=1e-3)
    ev = walk.step_events[0]
    assert ev.t == pytest.approx(g.step_time, abs=1e-5)
    inside = walk.t < min(ev.t, g.step_time)
    assert np.abs(walk.x[inside] - g.state(walk.t[inside])).max() <= 1e-2
    assert np.abs(ev.x_pre - g.pre_impact_state).max() <= 2e-4
    lc = find_fixed_point(s, g.fixed_point, params=P)
    assert lc.residual <= 1e-8
    assert np.abs(lc.fixed_point - g.fixed_point).max() <= 2e-4
    assert np.abs(lc.multipliers).max() < 1.0


@pytest.mark.slow
def test_rabbit_hzd_gait_walks_in_closed_loop():
    """Mesh 20 → 80 from standing still (the default start): the model's compiled HZD controller with the
    exported parameters walks the gait. The closed-loop state stays within 1e-4 of the collocated
    one, at the collocation points and along the step (the solution's Hermite interpolant);
    Newton on the closed-loop return map converges (residual ≤ 1e-8) within 1e-5 of the optimised
    fixed point. The fine mesh of the coarse closed-loop test above."""
    from amble import simulate
    from amble.analysis.poincare import find_fixed_point

    s = rabbit.build()
    g = optimize_gait(s, speed=SPEED, nodes=[20, 80], guess="stand", step_time=0.4)
    assert g.max_violation <= 1e-8
    assert np.abs(g.states[:, g.state_names.index("torso")]).max() < 0.5
    P = g.bezier["params"]
    walk = simulate(s, g.fixed_point, params=P, steps=1, sample_dt=2e-4)
    ev = walk.step_events[0]
    assert ev.t == pytest.approx(g.step_time, abs=1e-6)
    keep = walk.t < ev.t
    at = np.column_stack([np.interp(g.times[:-1], walk.t[keep], walk.x[keep, i]) for i in range(walk.x.shape[1])])
    assert np.abs(at - g.states[:-1]).max() <= 1e-4
    inside = walk.t < min(ev.t, g.step_time)
    assert np.abs(walk.x[inside] - g.state(walk.t[inside])).max() <= 1e-4
    assert np.abs(ev.x_pre - g.pre_impact_state).max() <= 1e-5
    lc = find_fixed_point(s, g.fixed_point, params=P)
    assert lc.residual <= 1e-8
    assert np.abs(lc.fixed_point - g.fixed_point).max() <= 1e-5
    assert np.abs(lc.multipliers).max() < 1.0


def test_rabbit_hzd_gait_from_the_interpolated_start():
    """The interpolated start (posture to its relabelling) still gives a feasible HZD gait."""
    s = rabbit.build()
    g = optimize_gait(s, speed=SPEED, nodes=10, guess="interpolate", step_time=0.4)
    assert g.max_violation <= 1e-8 and g.speed == pytest.approx(SPEED, rel=1e-9)
    assert np.abs(_outputs_on_gait(s, g)).max() <= 1e-8
