"""Parameters carry physical domains: unphysical values are refused before any work."""

from __future__ import annotations

import math

import pytest

import amble
from amble import NONNEGATIVE, POSITIVE, Model, ModelError, ParameterError, interval
from amble.cli.main import main
from amble.models import load


def test_domain_ends_open_and_closed():
    assert 0.0 not in POSITIVE and 1e-300 in POSITIVE
    assert 0.0 in NONNEGATIVE and -1e-300 not in NONNEGATIVE
    assert math.inf not in POSITIVE and math.nan not in NONNEGATIVE
    closed = interval(-1, 1, closed=True)
    assert 1.0 in closed and 1.0 not in interval(-1, 1)
    assert str(closed) == "[-1, 1]" and str(POSITIVE) == "(0, ∞)"


def test_a_default_outside_its_domain_is_a_model_error():
    m = Model("d")
    m.parameter("mass", -1.0)
    with pytest.raises(ModelError, match="outside"):
        m.restrict("mass", POSITIVE)
    with pytest.raises(ModelError, match="unknown parameter"):
        m.restrict("nope", POSITIVE)


@pytest.mark.parametrize("model, params", [
    ("compass-gait", {"m": -5.0}), ("compass-gait", {"a": -0.5}), ("compass-gait", {"g": 0.0}),
    ("compass-gait", {"g": -9.81}), ("compass-gait", {"slope": 1.5}), ("compass-gait", {"slope": 100.0}),
    ("rimless-wheel", {"alpha": 4.0}), ("humanoid-3d-yaw", {"I_xy": -1.0}), ("kneed-biped", {"It": -0.1}),
])
def test_unphysical_values_are_refused(model, params):
    with pytest.raises(ParameterError, match="outside its domain"):
        amble.simulate(load(model), params=params, steps=1)


def test_boundary_values_that_are_physical_pass():
    tr = amble.simulate(load("kneed-biped"), params={"It": 0.0, "Is": 0.0}, steps=1)  # point-mass segments
    assert tr.status == "completed"


def test_the_walker_slope_gets_a_domain_of_its_own():
    w = load("simplest-walker")
    assert w.modes[w.mode_names[0]].domain("slope") == amble.modelling.walker.SLOPES


def test_cli_refuses_before_any_work(capsys):
    assert main(["simulate", "compass-gait", "--set", "m=-5", "--steps", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "outside its domain (0, ∞)" in err[0]
    # a sweep whose range leaves the domain is refused before a point is computed
    assert main(["sweep", "compass-gait", "--param", "g=-1:1:3", "--scheduler", "synchronous"]) == 2
    assert "outside its domain" in capsys.readouterr().err
