"""Distances to a gait's basin boundary and the basin's share of a box, against independent
truth: the rimless wheel's boundary along its speed in closed form (energy), and the compass
gait's along one direction by bisection with Goswami's equations integrated by SciPy
(tests/oracles/compass_gait.py)."""

import json
import math

import numpy as np
import pytest
from oracles.compass_gait import fixed_point as goswami_fixed_point
from oracles.compass_gait import step as goswami_step

from amble import ConvergenceError, StateError, basin_measures
from amble.analysis.poincare import find_fixed_point
from amble.cli.args import load_model
from amble.cli.main import main

G, L, ALPHA, SLOPE = 9.81, 1.0, math.pi / 8, 0.08


@pytest.mark.parametrize("criterion", ["converge", "walk"])
def test_the_rimless_wheels_boundary_along_its_speed_is_the_speed_that_just_carries_it_over_the_top(criterion):
    s = load_model("rimless-wheel", derivatives=True)
    s.max_step_time = 60.0  # a step just over the top takes long; the model's 5 s would count it a fall
    lc = find_fixed_point(s)
    b = basin_measures(lc, samples=0, reach=0.5, xtol=1e-9, rtol=1e-10, atol=1e-10, criterion=criterion)
    # after an impact the stance spoke is at gamma - alpha: the hub passes over the top iff
    # w^2 > 2 (g/l)(1 - cos(gamma - alpha)) (energy); every faster wheel converges to the gait
    # (the energy map e' = cos^2(2 alpha) e + phi is a contraction), every slower one rocks back
    # and never steps again: returning to the gait and walking on have the same boundary
    w_fix = 1 / math.tan(2 * ALPHA) * math.sqrt(4 * G / L * math.sin(ALPHA) * math.sin(SLOPE))
    w_top = math.sqrt(2 * G / L * (1 - math.cos(SLOPE - ALPHA)))
    up, down = b.distances
    assert up["name"] == "+theta_dot" and up["distance"] is None and up["outside"] is None and up["reason"] == ""
    assert down["name"] == "-theta_dot" and down["reason"] != ""
    assert down["inside"] <= w_fix - w_top + 1e-10 and down["outside"] >= w_fix - w_top - 1e-10
    assert down["distance"] == pytest.approx(w_fix - w_top, abs=2e-9)
    assert b.section_coordinates == ["theta_dot"]


def test_the_rimless_wheels_box_share_is_the_share_above_the_top_speed():
    lc = find_fixed_point(load_model("rimless-wheel", derivatives=True))
    w_fix = lc.fixed_point[1]
    w_top = math.sqrt(2 * G / L * (1 - math.cos(SLOPE - ALPHA)))
    b = basin_measures(lc, [], samples=400, box=0.2, seed=1)
    # uniform in w* ± 0.2: inside iff w above w_top (a step needing more than the model's 5 s
    # counts as a fall, a band of ~1e-6 rad/s that 400 samples do not see)
    truth = (w_fix + 0.2 - w_top) / 0.4
    s = b.size
    assert s["ci_low"] < truth < s["ci_high"] and s["samples"] == 400
    assert s["box"]["theta_dot"] == pytest.approx([w_fix - 0.2, w_fix + 0.2])


def _goswami_returns(x, x_fix, slope=0.05, steps=60, tol=1e-4):
    """Whether a walk of Goswami's map from ``x`` (our coordinates) comes within ``tol`` of the gait."""
    z = np.array([-x[1], -x[0], -x[3], -x[2]])
    for _ in range(steps):
        try:
            z, _ = goswami_step(z, slope)
        except (ValueError, AssertionError):  # no heel strike within 5 s, or the swing leg behind
            return False
        if np.max(np.abs(z - x_fix)) < tol:
            return True
    return False


def test_the_compass_gaits_distance_along_a_speed_is_that_of_goswamis_equations():
    lc = find_fixed_point(load_model("compass-gait", derivatives=True))
    b = basin_measures(lc, [{"stance_dot": -1.0}], samples=0, xtol=1e-6)
    (d,) = b.distances
    assert d["direction"] == {"stance_dot": -1.0}
    x_fix = goswami_fixed_point(0.05)[0]

    def at(s):
        x = lc.fixed_point.copy()
        x[2] -= s
        return x

    lo, hi = 0.5 * d["distance"], 1.5 * d["distance"]
    assert _goswami_returns(at(lo), x_fix) and not _goswami_returns(at(hi), x_fix)
    while hi - lo > 1e-5:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _goswami_returns(at(mid), x_fix) else (lo, mid)
    assert d["distance"] == pytest.approx(0.5 * (lo + hi), abs=1e-5)


def test_a_direction_over_a_tied_coordinate_moves_its_partner_on_the_section():
    lc = find_fixed_point(load_model("compass-gait", derivatives=True))
    a = basin_measures(lc, [{"swing": -1.0}, {"stance": 1.0}], samples=0, xtol=1e-6).distances
    # stance + swing = 2 slope on the section: lowering the swing angle raises the stance angle
    assert a[0]["distance"] == pytest.approx(a[1]["distance"], abs=2e-6)
    # the walks shared by two threads give the same answers
    b = basin_measures(lc, [{"swing": -1.0}, {"stance": 1.0}], samples=0, xtol=1e-6, threads=2).distances
    assert a == b


@pytest.mark.parametrize("kw, what", [
    ({"directions": [{"knee": 1.0}]}, "unknown coordinate"),
    ({"directions": [{"stance": 0.0}]}, "not all zero"),
    ({"criterion": "survive"}, "criterion"),
    ({"steps": 0}, "steps"),
    ({"reach": -1.0}, "reach"),
    ({"box": {"swing": 0.1}}, "not section coordinates"),
])
def test_bad_requests_are_refused(kw, what):
    lc = find_fixed_point(load_model("compass-gait", derivatives=True))
    with pytest.raises(StateError, match=what):
        basin_measures(lc, **{"samples": 0, **kw})


def test_an_unstable_gait_has_no_basin():
    s = load_model("compass-gait", derivatives=True)
    lc = find_fixed_point(s, params={"slope": 0.09})  # past the period doubling: the period-1 gait is unstable
    if lc.stable:
        pytest.skip("the period-1 gait is still stable here")
    with pytest.raises(ConvergenceError, match="unstable"):
        basin_measures(lc)


def test_the_command_line_reports_the_basin_measures(capsys):
    args = ["robustness", "rimless-wheel", "--param", "slope", "--json", "--samples", "50", "--box", "0.1"]
    assert main(args) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["parameter"] == "slope" and d["gsn_state"] > 0
    names = [r["name"] for r in d["basin"]["distances"]]
    assert names == ["+theta_dot", "-theta_dot"] and d["basin"]["distances"][0]["distance"] is None
    assert d["basin"]["size"]["samples"] == 50 and d["basin"]["criterion"] == "converge"
    assert main(["robustness", "rimless-wheel", "--param", "slope", "--json", "--no-basin"]) == 0
    assert "basin" not in json.loads(capsys.readouterr().out)
    assert main(["robustness", "rimless-wheel", "--param", "slope", "--direction", "theta_dot=x"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.slow
def test_the_compass_gaits_box_share_counts_the_states_goswamis_equations_return_from():
    lc = find_fixed_point(load_model("compass-gait", derivatives=True))
    half = {"stance": 0.02, "stance_dot": 0.08, "swing_dot": 0.5}
    b = basin_measures(lc, [], samples=24, box=half, seed=5)
    # the same draws (uniform in the box over the section coordinates, stance + swing = 2 slope)
    rng = np.random.default_rng(5)
    u = rng.uniform(-1.0, 1.0, (24, 3)) * np.array(list(half.values()))
    x_fix = goswami_fixed_point(0.05)[0]
    count = 0
    for du in u:
        x = lc.fixed_point.copy()
        x[[0, 2, 3]] += du
        x[1] = 2 * 0.05 - x[0]
        count += _goswami_returns(x, x_fix)
    assert b.section_coordinates == list(half) and 0 < count < 24
    assert b.size["inside"] == count


def test_the_command_line_takes_the_boxs_half_width_per_section_coordinate(capsys):
    args = ["robustness", "compass-gait", "--param", "slope", "--json", "--samples", "8",
            "--direction", "stance_dot=-1", "--box", "stance=0.02, stance_dot=0.08,swing_dot=0.5"]
    assert main(args) == 0
    d = json.loads(capsys.readouterr().out)
    x = find_fixed_point(load_model("compass-gait", derivatives=True)).fixed_point
    box = d["basin"]["size"]["box"]
    assert list(box) == ["stance", "stance_dot", "swing_dot"]
    for name, i, h in (("stance", 0, 0.02), ("stance_dot", 2, 0.08), ("swing_dot", 3, 0.5)):
        assert box[name] == pytest.approx([x[i] - h, x[i] + h], abs=1e-9)
    for bad in ("stance=0.02,swing=0.1", "stance=0.02", "stance=x", "wide"):
        assert main([*args[:-1], bad]) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1
