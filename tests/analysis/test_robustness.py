"""The gait sensitivity norm from the exact return-map derivatives, against disturbed walks: the
rimless wheel's closed-form step map (tests/oracles/rimless_wheel_mfpt.py) and simulated walks of
the compass gait, both differenced centrally."""

import math

import numpy as np
import pytest
from oracles.rimless_wheel_mfpt import fixed_point, step

from amble import StateError
from amble.analysis.poincare import ReturnMap, find_fixed_point
from amble.analysis.robustness import gait_sensitivity
from amble.cli.args import load_model


def test_the_rimless_wheels_norm_is_that_of_its_closed_form_map():
    g = gait_sensitivity(find_fixed_point(load_model("rimless-wheel")), "slope")
    gamma, d = 0.08, 1e-6
    w = {}
    for sign in (1, -1):
        # one step on the ramp gamma + δ, then on gamma: the speeds after each step
        ws, prev, speeds = fixed_point(gamma), gamma, []
        for k in range(200):
            slope = gamma + sign * d if k == 0 else gamma
            ws, prev = step(np.array(ws), np.array(prev), np.array(slope)), slope
            speeds.append(float(ws))
        w[sign] = np.array(speeds)
    truth = math.sqrt(float(np.sum(((w[1] - w[-1]) / (2 * d)) ** 2)))
    assert g.coordinates["theta_dot"] == pytest.approx(truth, rel=1e-6)
    assert g.coordinates["theta"] == pytest.approx(1.0, rel=1e-9)  # the next step starts on the new ramp only


def test_the_compass_gaits_norm_is_that_of_simulated_disturbed_walks():
    s = load_model("compass-gait")
    lc = find_fixed_point(s)
    g = gait_sensitivity(lc, "slope")
    state, step_time = _disturbed_walks(s, lc, "slope", g.steps)
    assert g.state == pytest.approx(state, rel=1e-4)
    assert g.step_time == pytest.approx(step_time, rel=1e-4)


def _disturbed_walks(s, lc, name: str, steps: int, d: float = 1e-6) -> tuple[float, float]:
    """The norms of the response of simulated walks to one step with ``name`` ± ``d`` and
    ``steps`` undisturbed steps after it, differenced centrally: (state, step time)."""
    P = ReturnMap(s, lc.parameters)
    resp = {}
    for sign in (1, -1):
        x, t = ReturnMap(s, {**lc.parameters, name: lc.parameters[name] + sign * d})(lc.fixed_point)
        xs, ts = [x], [t]
        for _ in range(steps):
            x, t = P(x)
            xs.append(x)
            ts.append(t)
        resp[sign] = np.array(xs), np.array(ts)
    dx = (resp[1][0] - resp[-1][0]) / (2 * d)
    dt = (resp[1][1] - resp[-1][1]) / (2 * d)
    return math.sqrt(float(np.sum(dx**2))), math.sqrt(float(np.sum(dt**2)))


def test_an_unknown_parameter_is_refused():
    with pytest.raises(StateError, match="unknown parameter"):
        gait_sensitivity(find_fixed_point(load_model("rimless-wheel")), "friction")


def test_the_command_line_reports_the_norm_and_refuses_an_unknown_parameter(capsys):
    import json

    from amble.cli.main import main

    assert main(["robustness", "rimless-wheel", "--param", "slope", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["parameter"] == "slope" and d["gsn_coordinates"]["theta"] == pytest.approx(1.0)
    assert d["gsn_state"] >= d["gsn_coordinates"]["theta_dot"] > 0 and d["gsn_step_time"] > 0
    assert main(["robustness", "rimless-wheel", "--param", "mu"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    # the gait from a guess of its own and a tolerance: the same norm
    x = d["fixed_point"]
    guess = "x0=" + ",".join(f"{v + 1e-3:.12g}" for v in x)
    assert main(["robustness", "rimless-wheel", "--param", "slope", "--no-basin", "--json", "--guess", guess,
                 "--tol", "1e-11"]) == 0
    assert json.loads(capsys.readouterr().out)["gsn_state"] == pytest.approx(d["gsn_state"], rel=1e-8)
    for bad in (["--guess", "x0=1,a"], ["--guess", "nowhere"], ["--tol", "-1"]):
        assert main(["robustness", "rimless-wheel", "--param", "slope", "--no-basin", *bad]) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1


def _compass_with_a_step():
    """The library's compass gait whose footfall meets ground ``step`` (m) above the stance foot's
    slope plane: a parameter that disturbs one step as a step up or down."""
    from amble import walker
    from amble.models import compass_gait

    m = compass_gait.model()
    st, sw = m.q
    step = m.parameter("step", 0.0, "height of the ground the swing foot meets", "m")
    return walker(m, foot="swing_foot", hip="hip", slope=m.symbol("slope"), relabel={st: sw, sw: st},
                  start=[-0.2168, 0.3168, 1.0839, 0.3981], step_height=step)


def test_a_step_lands_the_foot_on_ground_that_high():
    """One step onto ground 2 cm lower: the swing foot strikes where its height above the slope
    plane is −0.02 m, and the walk goes on from the new stance foot."""
    from amble import simulate

    s = _compass_with_a_step()
    lc = find_fixed_point(s)
    run = simulate(s, lc.fixed_point, params={**lc.parameters, "step": -0.02}, steps=1)
    x = run.events[0].x_pre  # the state at the footfall, before the impact
    st, sw, a, b, gamma = x[0], x[1], 0.5, 0.5, lc.parameters["slope"]
    foot = (a + b) * np.array([np.sin(st) - np.sin(sw), np.cos(st) - np.cos(sw)])  # (x, z) of the swing foot
    normal = np.array([np.sin(gamma), np.cos(gamma)])  # the slope descends along +x
    assert float(foot @ normal) == pytest.approx(-0.02, abs=1e-10)


def test_the_compass_gaits_norm_for_a_step_down_is_that_of_disturbed_walks():
    """Hobbelen & Wisse's disturbance: one step onto ground ±δ high, then level walking again."""
    s = _compass_with_a_step()
    lc = find_fixed_point(s)
    g = gait_sensitivity(lc, "step")
    state, step_time = _disturbed_walks(s, lc, "step", g.steps)
    assert g.state == pytest.approx(state, rel=1e-4)
    assert g.step_time == pytest.approx(step_time, rel=1e-4)
    assert g.state > 1.0  # a centimetre's step moves the gait by centimetres: not a vanishing response
