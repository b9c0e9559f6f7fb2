"""Two-step (period-2) gaits: two phases, each with its own footfall, impact and relabelling,
periodic over the pair.

Truth, independent of the collocation: for a symmetric robot whose one-step optimum is unique
(the compass gait with hip and ankle torques at a fixed step length), the two-step optimum is two
copies of it; the passive compass gait on a 4.6° slope — between its first (4.39°) and second
(4.91°) period doublings (docs/references.md) — walks a period-2 gait of two different steps,
which Newton on amble's exact return map over two steps (``find_fixed_point(period=2)``) finds.
"""

import json

import numpy as np
import pytest

pytest.importorskip("casadi")

from amble.analysis.gait_optimisation import optimize_gait  # noqa: E402
from amble.analysis.poincare import find_fixed_point  # noqa: E402
from amble.errors import ParameterError  # noqa: E402
from amble.models import compass_gait  # noqa: E402

SLOPE = 0.0524


def actuated():
    s = compass_gait.build()
    m = s.modes["compass-gait"]
    st, sw = m.q
    m.actuator("hip", on=sw - st, limit=40.0)
    m.actuator("ankle", on=st, limit=20.0)
    return s


def test_two_step_optimum_of_a_symmetric_robot_is_the_one_step_optimum():
    one = optimize_gait(actuated(), params={"slope": SLOPE}, nodes=20, step_length=0.5)
    two = optimize_gait(actuated(), params={"slope": SLOPE}, nodes=20, step_length=0.5, steps=2)
    assert two.max_violation <= 1e-8 and len(two.steps) == 2
    assert two.objective == pytest.approx(one.objective, abs=1e-6)
    for step in two.steps:
        assert np.abs(step.fixed_point - one.fixed_point).max() <= 1e-6
        assert step.step_time == pytest.approx(one.step_time, abs=1e-6)


def test_period_two_passive_gait_is_the_return_maps_period_two_orbit(tmp_path):
    slope = np.deg2rad(4.6)
    s = compass_gait.build()
    g = optimize_gait(s, params={"slope": slope}, nodes=[20, 60], steps=2)
    assert g.max_violation <= 1e-8
    first, second = g.steps
    assert abs(first.step_time - second.step_time) > 0.01  # the steps differ
    assert np.abs(first.fixed_point - second.fixed_point).max() > 0.01
    lc = find_fixed_point(s, g.fixed_point, params={"slope": slope}, period=2)
    assert lc.period == 2 and lc.residual <= 1e-8
    orbit = np.asarray(lc.orbit)
    assert np.abs(orbit[0] - first.fixed_point).max() <= 1e-6
    assert np.abs(orbit[1] - second.fixed_point).max() <= 1e-6
    assert np.allclose(lc.step_times, [first.step_time, second.step_time], atol=1e-6)
    d = json.loads(g.save(tmp_path / "gait.json").read_text())
    assert d["period"] == 2 and len(d["steps"]) == 2
    assert np.allclose(d["steps"][1]["fixed_point"], second.fixed_point)


def test_steps_and_step_params_are_checked():
    s = compass_gait.build()
    with pytest.raises(ParameterError):
        optimize_gait(s, steps=0)
    with pytest.raises(ParameterError):
        optimize_gait(s, steps=2, step_params=[{}])
    with pytest.raises(ParameterError):
        optimize_gait(s, steps=2, step_params=[{}, {"nope": 1.0}])
