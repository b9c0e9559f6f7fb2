"""A trajectory's message reads as its status's template says, and a tolerance given to
simulate() is still checked (the ones taken from ``Options`` were checked when it was made)."""

import math

import pytest

import amble
from amble import StateError


def test_a_completed_walk_says_how_many_steps_and_how_long(compass_built):
    system, _ = compass_built
    for steps in (1, 3):
        tr = amble.simulate(system, steps=steps)
        assert tr.status == "completed" and tr.steps == steps
        # the walk ends at its last footfall: the last recorded row is the post-impact state
        assert tr.message == f"{steps} steps in {float(tr.t[-1]):.6g} s"


def test_a_run_to_its_end_time_says_where_it_stopped(compass_built):
    system, _ = compass_built
    tr = amble.simulate(system, t_end=0.25)
    assert tr.status == "end_time"
    assert tr.message == f"reached t = {0.25:.6g} s after {tr.steps} steps"


@pytest.mark.parametrize("name", ["rtol", "atol"])
@pytest.mark.parametrize("bad, match", [(-1e-8, "must be a positive number"), (0.0, "must be a positive number"),
                                        (math.inf, "must be a positive number"), ("1e-8", "must be a number"),
                                        (True, "must be a number")])
def test_a_given_tolerance_is_checked(compass_built, name, bad, match):
    system, _ = compass_built
    with pytest.raises(StateError, match=f"{name}.*{match}"):
        amble.simulate(system, steps=1, **{name: bad})
