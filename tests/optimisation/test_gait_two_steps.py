"""Two-step (period-2) gaits: two phases, each with its own footfall, impact and relabelling,
periodic over the pair.

Truth, independent of the collocation: for a symmetric robot whose one-step optimum is unique
(the compass gait with hip and ankle torques at a fixed step length), the two-step optimum is two
copies of it; the passive compass gait on a 4.6° slope — between its first and second period doublings
(4.37° and 4.9° printed by Goswami, Thuilot & Espiau; 4.391° and 4.914° re-computed,
docs/references.md) — walks a period-2 gait of two different steps,
which Newton on amble's exact return map over two steps (``find_fixed_point(period=2)``) finds.
"""

import json

import numpy as np
import pytest

pytest.importorskip("casadi")

from amble import POSITIVE, Model, R, walker  # noqa: E402
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


def uneven_legs():
    """The compass gait with a hip and an ankle torque whose legs' masses are parameters of their
    role: ``m1`` the stance leg's, ``m2`` the swing leg's (a robot with one heavier leg swaps them
    from one step to the next)."""
    m = Model("uneven-compass")
    st, sw = m.coordinates("stance swing")
    mh, m1, m2, a, b, g, slope = m.parameters(mh=10.0, m1=5.0, m2=5.0, a=0.5, b=0.5, g=9.81, slope=SLOPE)
    m.restrict("mh m1 m2 a b g", POSITIVE)
    m.point("stance_foot", (0, 0))
    hip = m.point("hip", (a + b) * R(st), mass=mh, link="stance_foot")
    m.point("stance_mass", b * R(st), mass=m1)
    m.point("swing_mass", hip - a * R(sw), mass=m2)
    m.point("swing_foot", hip - (a + b) * R(sw), link="hip")
    m.gravity(g)
    m.actuator("hip", on=sw - st, limit=40.0)
    m.actuator("ankle", on=st, limit=20.0)
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st},
                  start=[-0.2168, 0.3168, 1.0839, 0.3981])


def test_a_robot_with_one_heavier_leg_walks_two_different_steps():
    """Left leg 6.5 kg, right 3.5 kg, at a 0.5 m step: the two steps differ; the same robot seen
    from the other leg first (the step parameters in the other order) is the same period with its
    steps swapped — objective and each step's fixed point and time to 1e-6."""
    heavy, light = {"m1": 6.5, "m2": 3.5}, {"m1": 3.5, "m2": 6.5}
    g = optimize_gait(uneven_legs(), nodes=20, step_length=0.5, steps=2, step_params=[heavy, light])
    h = optimize_gait(uneven_legs(), nodes=20, step_length=0.5, steps=2, step_params=[light, heavy])
    assert g.max_violation <= 1e-8 and h.max_violation <= 1e-8
    assert np.abs(g.steps[0].fixed_point - g.steps[1].fixed_point).max() > 1e-2
    assert g.steps[0].params["m1"] == 6.5 and g.steps[1].params["m1"] == 3.5
    assert h.objective == pytest.approx(g.objective, abs=1e-6)
    for j in (0, 1):
        assert np.abs(h.steps[j].fixed_point - g.steps[1 - j].fixed_point).max() <= 1e-6
        assert h.steps[j].step_time == pytest.approx(g.steps[1 - j].step_time, abs=1e-6)


def test_steps_and_step_params_are_checked():
    s = compass_gait.build()
    with pytest.raises(ParameterError):
        optimize_gait(s, steps=0)
    with pytest.raises(ParameterError):
        optimize_gait(s, steps=2, step_params=[{}])
    with pytest.raises(ParameterError):
        optimize_gait(s, steps=2, step_params=[{}, {"nope": 1.0}])
