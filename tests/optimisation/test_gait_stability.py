"""Stability as a design constraint: RABBIT's HZD gait at 0.8 m/s with the multiplier of the
restricted Poincaré map bounded, ``δ_zero² ≤ 0.5``.

Truth the checks use, independent of the formula ``δ_zero² = (σ⁺/σ⁻)²`` that the optimisation
constrains:

* the theorem (Westervelt et al. 2007, Thm. 5.3): the closed-loop orbit lies on the hybrid-
  invariant zero-dynamics surface, so one full-order multiplier *is* the restricted map's for
  every output gain, and the transverse ones are small under a fast output controller (ε = 0.1:
  below 0.03 here) — the full-order multipliers come from Newton on amble's compiled closed loop
  and its variational equations, not from the momentum;
* the restricted map written out independently (``tests/oracles/rabbit_zero_dynamics.py``: the
  robot's equations by hand, the zero dynamics integrated in time with SciPy, the impact solved
  by hand, the multiplier by central differences of θ̇⁺ ↦ δ θ̇⁻).

The multiplier of the bounded gait depends only on the impact at ``θ⁻`` and the ends of the
step, which lie exactly on the surface, so it holds for the exported controller to the solver's
tolerance, not the collocation's: measured |λ_max − δ_zero²| = 2e-12 (the test allows 1e-7; the
oracle's central differences agree to 4e-10, allowed 1e-6).
"""

import json

import numpy as np
import pytest

pytest.importorskip("casadi")

from amble.analysis.gait_optimisation import optimize_gait  # noqa: E402
from amble.analysis.gait_stability import closed_loop_stability  # noqa: E402
from amble.errors import ParameterError  # noqa: E402
from amble.models import compass_gait, rabbit  # noqa: E402

SPEED, BOUND = 0.8, 0.5


@pytest.fixture(scope="module")
def gaits():
    s = rabbit.build()
    free = optimize_gait(s, speed=SPEED, nodes=10)
    bound = optimize_gait(s, speed=SPEED, nodes=10, max_multiplier=BOUND)
    return s, free, bound


def _oracle_multiplier(gait):
    """The restricted map's multiplier of the exported controller, from the independent oracle."""
    from oracles.rabbit_zero_dynamics import PARAMS, ZeroDynamics

    p = {**gait.params, **gait.bezier["params"]}
    alpha = [[p[f"alpha_{i}_{k}"] for k in range(6)] for i in range(4)]
    zd = ZeroDynamics(alpha, p["phase_start"], p["phase_end"], {k: p[k] for k in PARAMS})
    x = gait.fixed_point  # θ̇⁺ = torso_dot + stance_hip_dot + stance_knee_dot/2
    lc = zd.limit_cycle(guess=x[5] + x[6] + x[8] / 2)
    assert lc["residual"] < 1e-12
    return lc["multiplier"]


def test_the_bound_binds_and_changes_the_gait(gaits):
    """Without the bound the optimum's multiplier is above 0.5 (0.614); with it the multiplier is
    at the bound (an active constraint), the gait feasible at the same speed, and it costs effort."""
    _, free, bound = gaits
    assert free.stability["max_multiplier"] is None
    assert free.stability["restricted_multiplier"] > BOUND + 0.05
    assert "stability" not in free.constraints
    st = bound.stability
    assert st["max_multiplier"] == BOUND
    assert st["restricted_multiplier"] <= BOUND + 1e-8
    assert st["restricted_multiplier"] >= BOUND - 1e-6  # binding: the free optimum is above it
    assert bound.constraints["stability"]["active"] == 1
    assert bound.max_violation <= 1e-8 and bound.speed == pytest.approx(SPEED, rel=1e-9)
    assert bound.objective > free.objective
    assert json.loads(json.dumps(bound.to_json()))["stability"]["restricted_multiplier"] == st["restricted_multiplier"]


def test_the_closed_loops_multipliers_are_the_restricted_maps(gaits):
    """The full-order closed loop with the exported coefficients: its dominant multiplier is the
    constrained δ_zero² (the theorem), the independent oracle's restricted multiplier too; and
    the unconstrained gait's closed loop has its spectral radius above the bound."""
    s, free, bound = gaits
    cl = closed_loop_stability(s, bound)
    assert bound.stability["closed_loop"] is cl
    assert cl["residual"] <= 1e-8 and cl["fixed_point_distance"] <= 2e-4
    mods = np.abs([complex(*z) for z in cl["multipliers"]])
    assert mods[0] == cl["spectral_radius"]
    assert cl["spectral_radius"] == pytest.approx(bound.stability["restricted_multiplier"], abs=1e-7)
    assert mods[1] < 0.03  # ε = 0.1: the transverse multipliers are far below the restricted one
    assert _oracle_multiplier(bound) == pytest.approx(bound.stability["restricted_multiplier"], abs=1e-6)
    cl_free = closed_loop_stability(s, free)
    assert cl_free["spectral_radius"] == pytest.approx(free.stability["restricted_multiplier"], abs=1e-7)
    assert cl_free["spectral_radius"] > BOUND + 0.05


def test_the_bound_on_a_walker_whose_unactuated_direction_is_not_a_coordinate():
    """The compass gait with a hip torque only (``B ∝ (−1, 1)``): the unactuated direction is
    ``b⊥ ∝ (1, 1)``, turning both legs together (the angular momentum about the stance foot).
    Bounded at 0.6 (its free optimum at 0.8 m/s, 3°: 0.663), the gait walked by a controller of
    the exported virtual constraints (built here, ε = 0.005) has the bound as its dominant
    multiplier (measured to 1e-12) and the transverse ones at 1e-13."""
    from amble import find_fixed_point

    def hip_only():
        w = compass_gait.build()
        m = w.modes["compass-gait"]
        stance, swing = m.q
        m.actuator("hip", on=swing - stance)
        return w, m

    w, _ = hip_only()
    g = optimize_gait(w, params={"slope": 0.0524}, speed=0.8, nodes=[20, 60], bezier_degree=6, hzd=True,
                      max_multiplier=0.6)
    assert g.stability["restricted_multiplier"] == pytest.approx(0.6, abs=1e-8)
    bz = g.bezier
    loop, m = hip_only()
    m.virtual_constraints([m.parse(o) for o in bz["outputs"]], m.parse(bz["phase"]["expression"]), bz["alpha"],
                          (bz["phase"]["theta_plus"], bz["phase"]["theta_minus"]), epsilon=0.005)
    lc = find_fixed_point(loop, g.fixed_point, params={"slope": 0.0524})
    mods = np.sort(np.abs(lc.multipliers))[::-1]
    assert lc.residual <= 1e-8
    assert mods[0] == pytest.approx(g.stability["restricted_multiplier"], abs=1e-7)
    assert mods[1] < 1e-3


def test_stability_bound_errors():
    s = rabbit.build()
    for bad in (0.0, 1.0, float("nan"), -0.1):
        with pytest.raises(ParameterError, match="max_multiplier must be a number in"):
            optimize_gait(s, speed=SPEED, nodes=10, max_multiplier=bad)
    with pytest.raises(ParameterError, match="needs hzd=True"):
        optimize_gait(s, speed=SPEED, nodes=10, max_multiplier=0.5, hzd=False)
    # the compass gait driven at the ankle alone: the unactuated swing angle is not cyclic (the
    # kinetic energy couples it to the stance angle), so σ² / 2 is not the restricted map's coordinate
    w = compass_gait.build()
    m = w.modes["compass-gait"]
    m.actuator("ankle", on=m.q[0])
    with pytest.raises(ParameterError, match="coordinates only"):
        optimize_gait(w, params={"slope": 0.0524}, nodes=10, hzd=True, max_multiplier=0.5)


def test_max_multiplier_from_the_command_line(capsys, tmp_path):
    from amble.cli.main import main

    path = tmp_path / "gait.json"
    assert main(["optimize-gait", "rabbit", "--speed", "0.8", "--nodes", "10", "--max-multiplier", "0.5",
                 "--quiet", "--out", str(path)]) == 0
    out = capsys.readouterr().out
    assert "restricted Poincaré map multiplier δ_zero² 0.5 (bound 0.5); closed loop: spectral radius 0.5" in out
    st = json.loads(path.read_text())["stability"]
    assert st["restricted_multiplier"] <= 0.5 + 1e-8
    assert st["closed_loop"]["spectral_radius"] == pytest.approx(st["restricted_multiplier"], abs=1e-7)
    assert main(["optimize-gait", "rabbit", "--max-multiplier", "1.5"]) == 2
    assert "--max-multiplier must be in (0, 1)" in capsys.readouterr().err
