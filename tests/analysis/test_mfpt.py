"""The mean first-passage time of the rimless wheel on stochastic slopes, against a Monte Carlo
of its closed-form step map (tests/oracles/rimless_wheel_mfpt.py, nothing from amble)."""

import math

import pytest
from oracles.rimless_wheel_mfpt import monte_carlo_mfpt

from amble import POSITIVE, Guard, Model, ParameterError, R, distance_along_slope, height_above_slope, walker
from amble.analysis.mfpt import Terrain, mfpt
from amble.cli.main import main

ALPHA = math.pi / 8


def _wheel():
    """The library's rimless wheel, with rocking back onto the previous spoke a fall (as in the
    closed-form map: a wheel that cannot carry its hub over the top has stopped walking)."""
    m = Model("rimless-wheel-mfpt")
    (th,) = m.coordinates("theta")
    mass, l, g, alpha, slope = m.parameters(m=1.0, l=1.0, g=9.81, alpha=ALPHA, slope=0.08)
    m.restrict("m l g", POSITIVE)
    m.point("stance_foot", (0, 0))
    hub = m.point("hub", l * R(th), mass=mass)
    m.point("next_foot", hub - l * R(th - 2 * alpha))
    m.point("previous_foot", hub - l * R(th + 2 * alpha))
    m.gravity(g)
    s = walker(m, foot="next_foot", hip="hub", slope=slope, relabel={th: th - 2 * alpha},
               guess=[0.08 - ALPHA, 1.1])
    back = Guard(height_above_slope(m, "previous_foot", slope), -1, distance_along_slope(m, "previous_foot", slope) < 0)
    s.terminal("rocked_back", m.name, back, status="fell")
    return s


@pytest.mark.parametrize("sd", [0.02, 0.03, 0.04])
def test_the_rimless_wheels_mfpt_is_that_of_its_closed_form_map(sd):
    terrain = Terrain.parse(f"slope~normal(0.08,{sd})")
    r = mfpt(_wheel(), terrain, runs=20_000, max_steps=5_000, seed=7)
    truth = monte_carlo_mfpt(0.08, sd, 200_000, seed=11)
    assert r.censored == 0 and r.falls == 20_000
    assert r.ci_low < r.mfpt < r.ci_high and (r.ci_high - r.ci_low) / r.mfpt < 0.04  # ± 2 %
    # the oracle's own sampling error is a third of amble's (ten times the walks)
    assert abs(r.mfpt - truth) / truth < 0.02, (r.mfpt, truth)


def test_the_same_seed_gives_the_same_walks_and_a_steeper_spread_falls_sooner():
    s = _wheel()
    a = mfpt(s, Terrain.parse("slope~normal(0.08,0.03)"), runs=500, seed=3)
    b = mfpt(s, Terrain.parse("slope~normal(0.08,0.03)"), runs=500, seed=3)
    c = mfpt(s, Terrain.parse("slope~normal(0.08,0.05)"), runs=500, seed=3)
    assert a.to_json() == b.to_json()
    assert c.mfpt < a.mfpt


@pytest.mark.parametrize("text, what", [
    ("slope~gauss(0,1)", "not one of"),
    ("slope~normal(0.1,-1)", "standard deviation"),
    ("__import__('os')", "NAME~normal"),
    ("slope~normal(1e400,1)", "finite"),
    ("mu~normal(0,1)", "not parameters"),
])
def test_bad_terrains_are_refused(text, what):
    with pytest.raises(ParameterError, match=what):
        mfpt(_wheel(), Terrain.parse(text), runs=10)


def test_the_command_line_reports_the_mfpt_and_refuses_bad_terrain(capsys):
    import json

    assert main(["mfpt", "rimless-wheel", "--terrain", "slope~normal(0.08,0.04)", "--runs", "300", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["method"] == "montecarlo" and d["ci_low"] < d["mfpt"] < d["ci_high"] and d["runs"] == 300
    assert main(["mfpt", "rimless-wheel", "--terrain", "slope~normal(0.08)"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_a_walker_turned_round_by_the_terrain_has_fallen_and_the_estimate_ends():
    # the library's wheel rocks back onto its previous spoke as a transition, not a fall: on a
    # steep uphill draw it rolls back down without a footfall. Bounded by the walker's
    # max_step_time (5 s) each such walk is a fall within a second of computing; unbounded, it
    # rolled on to the integrator's step cap, ≈ 100 s for these 20 walkers (and a Markov chain's
    # tail probes of a wider law did not end in 10 minutes)
    import threading

    from amble.cli.args import load_model

    s, out = load_model("rimless-wheel"), {}
    work = threading.Thread(target=lambda: out.update(r=mfpt(
        s, Terrain.parse("slope~uniform(-0.3,-0.2)"), runs=20, max_steps=5, start=[0.08 - ALPHA, 1.5])),
        daemon=True)
    work.start()
    work.join(30)
    assert not work.is_alive(), "the Monte Carlo walk did not end"
    r = out["r"]
    assert r.falls == r.runs == 20 and r.censored == 0 and 1 <= r.mfpt <= 5
