"""The Markov-chain MFPT of the rimless wheel on stochastic slopes, against the converged chain on
the wheel's scalar energy (tests/oracles/rimless_wheel_mfpt.py, nothing from amble)."""

import pytest
from analysis.test_mfpt import _wheel
from oracles.rimless_wheel_mfpt import energy_mfpt

from amble import ParameterError
from amble.analysis.markov import markov_mfpt
from amble.analysis.mfpt import Terrain


def _check(mean, sd, **kw):
    r = markov_mfpt(_wheel(), Terrain.parse(f"slope~normal({mean},{sd})"), **kw)
    truth = energy_mfpt(mean, sd, 1000)
    assert abs(r.mfpt - truth) / truth < 0.02, (r.mfpt, truth, r.levels)
    return r


def test_the_rimless_wheels_markov_mfpt_is_that_of_its_energy_chain():
    r = _check(0.08, 0.03, nodes=32, spacing=0.05, levels=2)
    # the refinement is shown: one value per spacing, each half the one before, the finest last
    assert [lv["spacing"] for lv in r.levels] == [0.1, 0.05] and r.levels[-1]["mfpt"] == r.mfpt
    assert r.levels[0]["states"] < r.levels[1]["states"] == r.states and all(lv["complete"] for lv in r.levels)
    assert r.ci_low <= r.mfpt <= r.ci_high
    # the metastable distribution is a distribution on the mesh; from it the walker falls at 1 − λ₂
    assert r.metastable.shape == (r.states,) and abs(r.metastable.sum() - 1) < 1e-12
    assert 0 < r.lambda2 < 1 and r.mfpt_eigen == pytest.approx(1 / (1 - r.lambda2))


@pytest.mark.parametrize("mean, sd", [(0.08, 0.02), (0.08, 0.04)])
def test_the_wheel_on_more_slopes(mean, sd):
    _check(mean, sd, nodes=32, spacing=0.05, levels=1)


@pytest.mark.slow
@pytest.mark.parametrize("mean, sd", [(0.1, 0.05), (0.12, 0.05), (0.08, 0.015)])
def test_the_wheel_on_wider_laws_with_more_nodes(mean, sd):
    # a wide law needs more terrain nodes: 32 nodes are 1.7 % and 2.4 % off at sd 0.05
    _check(mean, sd, nodes=64, spacing=0.05, levels=1)


@pytest.mark.parametrize("kw, what", [
    ({"nodes": 0}, "nodes"), ({"levels": 1.5}, "levels"), ({"spacing": -1.0}, "spacing"),
    ({"bisections": -1}, "bisections"), ({"mesh": "grid"}, "mesh"),
])
def test_bad_settings_are_refused(kw, what):
    with pytest.raises(ParameterError, match=what):
        markov_mfpt(_wheel(), Terrain.parse("slope~normal(0.08,0.03)"), **kw)


def test_the_command_line_gives_the_markov_estimate_its_levels_and_a_plot(capsys, tmp_path):
    import json

    from amble.cli.main import main

    png = tmp_path / "metastable.png"
    assert main(["mfpt", "rimless-wheel", "--terrain", "slope~normal(0.08,0.04)", "--method", "markov",
                 "--nodes", "16", "--spacing", "0.2", "--levels", "2", "--plot", str(png), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["method"] == "markov" and d["ci_low"] <= d["mfpt"] <= d["ci_high"]
    assert [lv["spacing"] for lv in d["levels"]] == [0.4, 0.2] and d["state_names"] == ["theta", "theta_dot"]
    assert len(d["metastable"]["mean"]) == 2 and 0 < d["metastable"]["mode_probability"] <= 1
    assert png.read_bytes()[:4] == b"\x89PNG"
    for bad in (["--spacing", "0"], ["--nodes", "0"], ["--plot", str(tmp_path / "x.txt")]):
        assert main(["mfpt", "rimless-wheel", "--terrain", "slope~normal(0.08,0.04)", "--method", "markov", *bad]) == 2
        assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert main(["mfpt", "rimless-wheel", "--terrain", "slope~normal(0.08,0.04)", "--plot", str(png)]) == 2


def _agree(terrain, runs, **kw):
    """Monte Carlo and the chain on the compass gait: the chain's stated interval (its two finest
    levels and, where they converge as a power of the spacing, their Richardson limit) overlaps
    the 95 % interval of simulated walks, and every level's mesh holds every reachable state."""
    from amble.analysis.mfpt import mfpt
    from amble.cli.args import load_model

    s = load_model("compass-gait")
    mc = mfpt(s, Terrain.parse(terrain), runs=runs, seed=1, max_steps=2000)
    chain = markov_mfpt(s, Terrain.parse(terrain), **kw)
    assert all(lv["complete"] for lv in chain.levels), chain.levels
    assert chain.ci_low <= chain.mfpt <= chain.ci_high
    assert chain.ci_low <= mc.ci_high and mc.ci_low <= chain.ci_high, (chain.levels, chain.extrapolated,
                                                                       mc.ci_low, mc.ci_high)
    return mc, chain


def test_the_compass_gaits_markov_and_monte_carlo_mfpt_agree():
    # 20 000 walkers: 6.1 steps, interval ±1.4 %; the chain: 470, 1660 and 6540 mesh states
    _agree("slope~normal(0.0525,0.015)", 20_000, nodes=8, spacing=0.2, levels=3)


@pytest.mark.slow
def test_the_compass_gaits_chain_agrees_on_a_narrower_law():
    # 20 000 walkers: 8.9 steps, interval ±1.4 %; the chain: 16 nodes, up to 28 000 mesh states (3 min, 1 GB)
    _agree("slope~normal(0.0525,0.01)", 20_000, nodes=16, spacing=0.2, levels=3, max_states=40_000)


def test_the_chain_of_every_state_coordinate_is_kept():
    # every state coordinate compared (the wheel's θ and θ̇ in one Delaunay triangulation)
    _check(0.08, 0.03, nodes=32, spacing=0.05, levels=1, mesh="state")


def test_richardsons_limit_of_a_geometric_refinement():
    from amble.analysis.markov import _extrapolate

    # errors 1, 1/2, 1/4 of a first-order method: the limit 2 and the order 1, exactly
    assert _extrapolate([1.0, 1.5, 1.75]) == (2.0, 1.0)
    limit, order = _extrapolate([5.0, 8.0, 8.75])  # errors 4, 1, 1/4: second order
    assert limit == pytest.approx(9.0) and order == pytest.approx(2.0)
    # no limit claimed where the differences grow or change sign, or from two levels
    assert _extrapolate([1.0, 1.2, 1.6]) == (None, None) and _extrapolate([1.0, 1.5, 1.4]) == (None, None)
    assert _extrapolate([1.0, 1.5]) == (None, None)


def test_the_oracles_energy_chain_is_the_monte_carlo_of_its_map():
    from oracles.rimless_wheel_mfpt import monte_carlo_mfpt

    truth = energy_mfpt(0.08, 0.03, 1000)
    assert abs(energy_mfpt(0.08, 0.03, 500) - truth) < 1e-3  # converged in the cells
    mc = monte_carlo_mfpt(0.08, 0.03, 400_000, seed=3)  # standard error 0.17 %
    assert abs(mc - truth) / truth < 0.007, (mc, truth)


def test_a_walker_on_ground_that_never_changes_never_falls():
    r = markov_mfpt(_wheel(), Terrain.parse("slope~normal(0.08,0)"), nodes=4, levels=2)
    assert r.mfpt == float("inf") and r.to_json()["mfpt"] is None and r.to_json()["levels"][0]["mfpt"] is None
