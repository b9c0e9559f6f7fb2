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
    d = 1e-6
    P = ReturnMap(s, lc.parameters)
    resp = {}
    for sign in (1, -1):
        Pd = ReturnMap(s, {**lc.parameters, "slope": lc.parameters["slope"] + sign * d})
        x, t = Pd(lc.fixed_point)
        xs, ts = [x], [t]
        for _ in range(g.steps):
            x, t = P(x)
            xs.append(x)
            ts.append(t)
        resp[sign] = np.array(xs), np.array(ts)
    dx = (resp[1][0] - resp[-1][0]) / (2 * d)
    dt = (resp[1][1] - resp[-1][1]) / (2 * d)
    assert g.state == pytest.approx(math.sqrt(float(np.sum(dx**2))), rel=1e-4)
    assert g.step_time == pytest.approx(math.sqrt(float(np.sum(dt**2))), rel=1e-4)


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
