"""check_gait against closed forms: the rimless wheel's hub rides a massless spoke, so the
ground pushes along the spoke with F = m (g cos θ − l θ̇²)."""

import math

import numpy as np
import pytest

from amble.analysis.gait_check import check_gait, ground_reaction
from amble.analysis.poincare import find_fixed_point
from amble.models import load


@pytest.fixture(scope="module")
def wheel_walk():
    lc = find_fixed_point(load("rimless-wheel"))
    return lc.trajectory(steps=3)


def test_ground_reaction_of_the_rimless_wheel_is_along_the_spoke(wheel_walk):
    tr = wheel_walk
    p = tr.parameters
    th, thd = tr.column("theta"), tr.column("theta_dot")
    F, Fn, Ft = ground_reaction(tr)
    along = p["m"] * (p["g"] * np.cos(th) - p["l"] * thd**2)
    np.testing.assert_allclose(F[:, 0], along * np.sin(th), atol=1e-9)
    np.testing.assert_allclose(F[:, 2], along * np.cos(th), atol=1e-9)
    np.testing.assert_allclose(Fn, along * np.cos(th - p["slope"]), atol=1e-9)
    np.testing.assert_allclose(Ft, np.abs(along * np.sin(th - p["slope"])), atol=1e-9)


def test_check_gait_of_the_rimless_wheel(wheel_walk):
    c = check_gait(wheel_walk)
    a = math.pi / 8
    assert c.max_friction_ratio == pytest.approx(math.tan(a), rel=1e-3)  # |θ − γ| ≤ α
    assert c.ok and c.friction_ok and c.impulse_positive and c.trailing_foot_leaves
    assert not check_gait(wheel_walk, mu=0.3).friction_ok  # tan(π/8) = 0.414 > 0.3
    assert c.max_input_ratio == 0.0


def test_check_gait_of_the_controlled_compass_gait():
    lc = find_fixed_point(load("compass-gait-level"))
    c = check_gait(lc.trajectory())
    assert c.normal_force_positive and c.impulse_positive and c.trailing_foot_leaves
    assert c.to_json()["ok"] == c.ok


def test_limit_cycle_json_reports_the_checks_of_an_actuated_model(capsys):
    import json

    from amble.cli.main import main

    assert main(["limit-cycle", "compass-gait-level", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["stable"] and out["checks"]["normal_force_positive"] and out["checks"]["mu"] == 0.7
    assert out["checks"]["max_friction_ratio"] > 0
