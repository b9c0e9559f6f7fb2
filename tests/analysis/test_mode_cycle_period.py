"""A walker whose stance feet are modes (left → right → left) has gaits of an even number of
footfalls: its period follows from its mode cycle without being asked for.

Truth: the compass gait written out by hand in Goswami's form and integrated with SciPy
(tests/oracles/compass_gait.py) for the fixed point and the step time; for the multipliers, the
theorem that the two-footfall map of the one-mode walker (which relabels the legs itself) is the
square of its one-footfall map, so its multipliers are the squares of the one-footfall ones.
"""

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from two_mode_walkers import compass_two_modes

from amble.analysis.mode_cycle import footfall_cycle, section_period
from amble.analysis.poincare import _lower_period, find_fixed_point
from amble.analysis.return_map import ReturnMap
from amble.cli.main import main
from amble.errors import StateError
from amble.models import load
from amble.simulation.engine import run

MODEL_FILE = f"{Path(__file__).parents[1] / 'two_mode_walkers.py'}:compass_two_modes"
ONE_FOOTFALL = "period 1: a gait of compass-two-modes returns to mode 'left' after a multiple of 2 footfalls " \
               "(left → right → left)"


def _goswami(x: np.ndarray) -> np.ndarray:
    """amble's compass state (stance, swing, their rates; positive downhill) in the oracle's
    (swing, stance, their rates; counter-clockwise positive); the map is its own inverse."""
    return np.array([-x[1], -x[0], -x[3], -x[2]])


def _sorted(m: np.ndarray) -> np.ndarray:
    return np.array(sorted(np.asarray(m, complex), key=lambda z: (round(abs(z), 6), z.imag)))


@pytest.fixture(scope="module")
def two():
    return compass_two_modes()


@pytest.fixture(scope="module")
def gait(two):
    return find_fixed_point(two)


def _system(name, modes, *transitions):
    """A system as the cycle reads it: modes and (source, target, step, terminal) transitions."""
    trs = [SimpleNamespace(source=s, target=t, step=step, terminal=term) for s, t, step, term in transitions]
    return SimpleNamespace(name=name, modes=dict.fromkeys(modes), mode_names=list(modes), transitions=trs)


def test_the_footfall_cycle_follows_steps_through_the_other_transitions(two):
    assert footfall_cycle(two) == ["left", "right"]
    assert footfall_cycle(two, "right") == ["right", "left"]
    # a kneed biped: the knee lock changes the mode between footfalls, not the section's mode
    kneed = _system("kneed", ["unlocked", "locked"], ("unlocked", "locked", False, None),
                    ("locked", "unlocked", True, None), ("unlocked", "unlocked", False, "scuffed"))
    assert footfall_cycle(kneed) == ["unlocked"] and section_period(kneed, None) == 1
    # three stance modes taken in turn (a tripod's feet)
    tripod = _system("tripod", "abc", ("a", "b", True, None), ("b", "c", True, None), ("c", "a", True, None))
    assert footfall_cycle(tripod) == ["a", "b", "c"] and section_period(tripod, None) == 3
    with pytest.raises(StateError, match=r"after a multiple of 3 footfalls \(a → b → c → a\)"):
        section_period(tripod, 4)
    # footfalls into either of two modes: no unique cycle, the period is the caller's
    branching = _system("branching", "ab", ("a", "a", True, None), ("a", "b", True, None), ("b", "a", True, None))
    assert footfall_cycle(branching) is None and section_period(branching, None) == 1
    assert section_period(branching, 3) == 3
    # footfalls that never lead back to the first mode
    away = _system("away", "ab", ("a", "b", True, None), ("b", "b", True, None))
    assert footfall_cycle(away) is None


def test_library_walkers_keep_a_cycle_of_one_footfall():
    assert footfall_cycle(load("compass-gait")) == ["compass-gait"]
    assert footfall_cycle(load("kneed-biped")) == ["unlocked"]


def test_two_stance_modes_default_to_two_footfalls_on_goswamis_gait(gait):
    from oracles.compass_gait import fixed_point, step

    assert gait.period == 2 and gait.requested_period is None and gait.mode == "left"
    x, _ = fixed_point(0.05)
    np.testing.assert_allclose(gait.fixed_point, _goswami(x), rtol=0, atol=1e-9)
    _, t = step(x, 0.05)
    # the step time is per footfall, and both footfalls of the symmetric gait take it
    assert gait.step_time == pytest.approx(t, abs=1e-9)
    np.testing.assert_allclose(gait.step_times, [t, t], rtol=0, atol=1e-9)


def test_multipliers_are_the_squares_of_the_one_mode_walkers(gait):
    one = load("compass-gait")
    lc1 = find_fixed_point(one)
    assert lc1.period == 1
    np.testing.assert_allclose(lc1.fixed_point, gait.fixed_point, rtol=0, atol=1e-9)
    assert lc1.step_time == pytest.approx(gait.step_time, abs=1e-9)
    np.testing.assert_allclose(_sorted(gait.multipliers), _sorted(lc1.multipliers ** 2), rtol=0, atol=1e-8)
    # and those of the one-mode walker's own two-footfall map at its gait
    A, _, _ = ReturnMap(one, period=2).section_jacobian(lc1.fixed_point)
    np.testing.assert_allclose(_sorted(gait.multipliers), _sorted(np.linalg.eigvals(A)), rtol=0, atol=1e-8)


def test_a_period_that_is_not_a_multiple_of_the_cycle_is_refused_before_any_run(two):
    with pytest.raises(StateError) as e:
        find_fixed_point(two, period=1)
    assert str(e.value) == ONE_FOOTFALL
    with pytest.raises(StateError, match="period 3: .* multiple of 2 footfalls"):
        ReturnMap(two, period=3)


def test_four_footfalls_reduce_to_two_not_one(two, gait):
    lc = find_fixed_point(two, gait.fixed_point, period=4)
    assert lc.period == 2 and lc.requested_period == 4
    np.testing.assert_allclose(lc.fixed_point, gait.fixed_point, rtol=0, atol=1e-9)
    P4 = ReturnMap(two, period=4)
    # one footfall on, the symmetric gait's state has the fixed point's very numbers, in the
    # other mode: only the mode tells it from a one-footfall gait
    r = run(P4.k, P4.p, P4.mi, gait.fixed_point, steps=1, opts=P4.opts)
    assert r.completed and r.mode != P4.mi
    np.testing.assert_allclose(r.x, gait.fixed_point, rtol=0, atol=1e-9)
    assert _lower_period(P4, gait.fixed_point, 4, 1e-11) == 2


def test_limit_cycle_cli_finds_the_two_footfall_gait_without_being_told(capsys, gait):
    code = main(["limit-cycle", MODEL_FILE, "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    d = json.loads(out.out)
    assert d["period"] == 2 and d["requested_period"] == 2 and len(d["step_times"]) == 2
    np.testing.assert_allclose(d["fixed_point"], gait.fixed_point, rtol=0, atol=1e-9)
    code = main(["limit-cycle", MODEL_FILE, "--period", "1"])
    out = capsys.readouterr()
    assert code == 2 and out.out == ""
    assert out.err.strip().splitlines() == [f"amble: error: {ONE_FOOTFALL}"]


def test_gaits_of_two_stance_modes_are_searched_at_multiples_of_two_footfalls(capsys, two, gait):
    from amble.analysis.gaits import find_gaits

    found = find_gaits(two, seeds=0)
    assert found.max_period == 2 and [g.period for g in found] == [2]
    np.testing.assert_allclose(found[0].fixed_point, gait.fixed_point, rtol=0, atol=1e-9)
    with pytest.raises(StateError, match="period 1: .* multiple of 2 footfalls"):
        find_gaits(two, period=1, seeds=0)
    code = main(["gaits", MODEL_FILE, "--period", "1"])
    out = capsys.readouterr()
    assert code == 2 and out.err.strip().splitlines() == [f"amble: error: {ONE_FOOTFALL}"]
