"""Every gait at one set of parameters (amble.find_gaits), against published and independent values.

* The simplest walker at γ = 0.009 has two period-1 gaits (Garcia, Chatterjee, Ruina & Coleman
  1998, "The simplest walking model: stability, complexity, and scaling", J. Biomech. Eng. 120:
  281–288; the numbers printed by the simulation code distributed with the paper, see
  docs/references.md section 2 and tests/models/test_simplest_walker.py): the stable long-period
  gait θ* = 0.20031090049483, θ̇* = −0.19983247291764 with eigenvalues −0.1912 ± 0.5563i, and the
  unstable short-period gait θ* = 0.19393736960624, θ̇* = −0.20386692731962 with eigenvalues
  4.000 and 0.459. Both are also computed here by Garcia's equations integrated with SciPy
  (tests/oracles/simplest_walker.py, nothing from amble).
* The compass gait past its first period doubling (slope ≈ 0.07665 rad, Goswami, Thuilot &
  Espiau 1998): the period-1 gait is unstable (a multiplier below −1) and a stable period-2 gait
  exists. Both are checked against Goswami's equations integrated with SciPy
  (tests/oracles/compass_gait.py): the oracle's step map takes each point of amble's orbit to the
  next one, and the oracle's own Newton gives the period-1 fixed point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import amble
from amble.analysis.gaits import _deflation, find_gaits, halton
from amble.cli.main import main
from amble.errors import StateError
from amble.models import load

GAMMA = 0.009
GARCIA_LONG = (0.20031090049483, -0.19983247291764)
GARCIA_LONG_EIG = complex(-0.19120868949940, 0.55633363687106)
GARCIA_SHORT = (0.19393736960624, -0.20386692731962)
GARCIA_SHORT_EIG = (4.000, 0.459)
#: past the compass gait's first period doubling (≈ 0.07665 rad)
PAST_FLIP = 0.078


@pytest.fixture(scope="module")
def simplest():
    return load("simplest-walker")


@pytest.fixture(scope="module")
def garcia(simplest):
    return find_gaits(simplest, params={"slope": GAMMA})


def _key(z: complex) -> tuple[float, float]:
    return (abs(z), z.imag)


def test_the_simplest_walker_shows_both_of_garcias_gaits(garcia):
    assert [g.period for g in garcia] == [1, 1]
    long, short = garcia  # stable first
    assert long.stable and not short.stable
    for g, (th, thd) in ((long, GARCIA_LONG), (short, GARCIA_SHORT)):
        assert g.fixed_point[0] == pytest.approx(th, abs=1e-9)
        assert g.fixed_point[2] == pytest.approx(thd, abs=1e-9)
        assert g.residual < 1e-10
    # Garcia's printed eigenvalues carry about 1e-3 of error (the oracle's agree with ours to 1e-8)
    assert min(abs(m - GARCIA_LONG_EIG) for m in long.multipliers) < 2e-3
    np.testing.assert_allclose(sorted(abs(short.multipliers), reverse=True), GARCIA_SHORT_EIG, atol=5e-3)


def test_garcias_gaits_agree_with_an_independent_implementation(garcia):
    from oracles.simplest_walker import LONG_GUESS, SHORT_GUESS, limit_cycle

    for g, guess in zip(garcia, (LONG_GUESS, SHORT_GUESS)):
        ref = limit_cycle(GAMMA, guess)
        np.testing.assert_allclose(g.fixed_point, ref["fixed_point"], rtol=0, atol=1e-10)
        assert g.step_time == pytest.approx(ref["step_time"], abs=1e-9)
        np.testing.assert_allclose(sorted(g.multipliers, key=_key), sorted(ref["multipliers"], key=_key), atol=1e-7)


def test_a_period_two_search_reports_no_gait_twice(simplest):
    """Below its first period doubling (γ ≈ 0.0151) the simplest walker has no period-2 gait: a
    period-2 search must report the two period-1 gaits once each, not their repetitions."""
    found = find_gaits(simplest, params={"slope": GAMMA}, period=2, seeds=8)
    assert [g.period for g in found] == [1, 1]
    assert abs(found[0].fixed_point[0] - found[1].fixed_point[0]) > 1e-3


def _goswami(x: np.ndarray) -> np.ndarray:
    """amble's compass state (stance, swing, stance_dot, swing_dot; positive downhill) in the
    oracle's (swing, stance, their rates; counter-clockwise positive)."""
    return np.array([-x[1], -x[0], -x[3], -x[2]])


def test_compass_gait_past_its_first_period_doubling():
    from oracles.compass_gait import fixed_point, step

    found = find_gaits(load("compass-gait"), params={"slope": PAST_FLIP}, period=2, seeds=16)
    ones = [g for g in found if g.period == 1]
    twos = [g for g in found if g.period == 2]
    # the period-1 gait continued from the library's default (the oracle's Newton finds it)
    ref = _goswami(fixed_point(PAST_FLIP)[0])  # amble ↔ oracle is an involution
    one = min(ones, key=lambda g: float(np.max(np.abs(g.fixed_point - ref))))
    np.testing.assert_allclose(one.fixed_point, ref, rtol=0, atol=1e-8)
    assert not one.stable and min(m.real for m in one.multipliers) < -1.0
    assert len(twos) == 1
    two = twos[0]
    assert two.stable and two.residual < 1e-10
    a, b = two.orbit
    assert np.max(np.abs(a - b)) > 1e-3  # two distinct points, not the period-1 gait repeated
    # the oracle's step map takes each point of the orbit to the other, with amble's step times
    for x, y, dt in ((a, b, two.step_times[0]), (b, a, two.step_times[1])):
        nxt, t = step(_goswami(x), PAST_FLIP)
        np.testing.assert_allclose(_goswami(nxt), y, rtol=0, atol=1e-8)
        assert t == pytest.approx(dt, abs=1e-8)


def test_seeds_that_fall_are_counted_not_raised(simplest):
    # thrown backwards: the walker falls before any heel strike
    found = find_gaits(simplest, seeds=[[0.2, 0.4, 2.0, 0.0]])
    assert list(found) == [] and found.fell == 1 and found.seeds == 1


def test_the_deflation_gradient_is_that_of_the_log_of_the_operator():
    """∇ ln M for M(x) = ∏ (‖x − xᵢ‖⁻² + 1): central differences of its closed form."""
    rng = np.random.default_rng(1)
    known = [rng.normal(size=3) for _ in range(2)]
    x = rng.normal(size=3)

    def log_m(z):
        return sum(math.log(np.sum((z - xi) ** 2) ** -1 + 1.0) for xi in known)

    fd = [(log_m(x + 1e-6 * e) - log_m(x - 1e-6 * e)) / 2e-6 for e in np.eye(3)]
    np.testing.assert_allclose(_deflation(x, known), fd, rtol=1e-7)


def test_halton_points_are_the_radical_inverses():
    np.testing.assert_allclose(halton(4, 2, None), [[1 / 2, 1 / 3], [1 / 4, 2 / 3], [3 / 4, 1 / 9], [1 / 8, 4 / 9]])
    shifted = halton(4, 2, 7)
    assert np.all((shifted >= 0) & (shifted < 1))
    np.testing.assert_array_equal(shifted, halton(4, 2, 7))  # reproducible


def test_bad_input_is_refused(simplest):
    with pytest.raises(StateError):
        find_gaits(simplest, period=0)
    with pytest.raises(StateError):
        find_gaits(simplest, seeds=[[0.2, 0.4]])  # a state of the wrong length


def test_package_root_exports_it():
    assert amble.find_gaits is find_gaits


def test_cli_gaits(capsys):
    import json

    assert main(["gaits", "simplest-walker", "--set", f"slope={GAMMA}", "--seeds", "8", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [g["stable"] for g in out["gaits"]] == [True, False]
    for g, (th, thd) in zip(out["gaits"], (GARCIA_LONG, GARCIA_SHORT)):
        assert g["period"] == 1 and len(g["multipliers"][0]) == 2
        assert g["fixed_point"][0] == pytest.approx(th, abs=1e-9)
        assert g["fixed_point"][2] == pytest.approx(thd, abs=1e-9)
        assert g["step_time"] > 0
    for bad in (["--period", "0"], ["--tol", "0"], ["--seeds", "-1"], ["--guess", "1,2"]):
        assert main(["gaits", "simplest-walker", *bad]) == 2
        assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.slow
def test_period_three_orbits_found_are_orbits_of_an_independent_map():
    """Near the end of the compass gait's cascade (slope 0.087) a period-3 search finds saddle
    period-3 orbits; the oracle's own step map brings each back to its start in three steps."""
    from oracles.compass_gait import step

    found = find_gaits(load("compass-gait"), params={"slope": 0.087}, period=3, seeds=24)
    threes = [g for g in found if g.period == 3]
    assert threes
    for g in threes:
        x = y = _goswami(g.fixed_point)
        for dt in g.step_times:
            y, t = step(y, 0.087)
            assert t == pytest.approx(dt, abs=1e-8)
        np.testing.assert_allclose(y, x, rtol=0, atol=1e-9)
