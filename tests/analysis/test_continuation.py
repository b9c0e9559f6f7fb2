"""Pseudo-arclength continuation: residuals, the compass gait's period doubling against the
normal form of a flip fitted to brute-force period-2 orbits, against the 4.37° printed by Goswami,
Thuilot & Espiau and against a SciPy re-computation of their equations (tests/oracles), the
kneed biped's fold against brute-force existence, branch switching and the CLI kind."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest

from amble.analysis.bifurcation import poincare_iterates
from amble.analysis.bifurcation_location import _tests
from amble.analysis.continuation import cascade, continue_branch
from amble.analysis.poincare import ReturnMap, find_fixed_point
from amble.analysis.section import Section
from amble.cli.main import main
from amble.errors import ConvergenceError
from amble.models import load

#: Hsu Chen (2007) Table 3.1, the kneed walker's published parameter set
HSU_CHEN = dict(mh=0.5, mt=0.5, ms=0.05, a1=0.375, b1=0.125, a2=0.175, b2=0.325, g=9.8)


@pytest.fixture(scope="module")
def compass():
    return load("compass-gait")


@pytest.fixture(scope="module")
def kneed():
    return load("kneed-biped")


@pytest.fixture(scope="module")
def flip_branch(compass):
    return continue_branch(compass, "slope", 0.074, 0.079)


def _fd_multipliers(system, x, params, h=1e-5):
    """Multipliers from central differences of the return map along an orthonormal basis of the
    section's tangent space (independent of the variational equations)."""
    P = ReturnMap(system, params)
    U = Section.of(P, x).tangent()
    cols = [(P(x + h * U[:, j])[0] - P(x - h * U[:, j])[0]) / (2 * h) for j in range(U.shape[1])]
    return np.linalg.eigvals(U.T @ np.array(cols).T)


def test_branch_points_are_gaits(compass, flip_branch):
    br = flip_branch
    assert br.end == "reached the end of the range"
    assert br.points[0].value == 0.074 and br.points[-1].value == pytest.approx(0.079, abs=1e-14)
    assert np.all(np.diff(br.values()) > 0)  # no fold here: the slope grows along the branch
    for p in br.points:
        assert p.residual < 1e-10
    for p in br.points[::20]:  # an independent step of the recorded simulation returns to the state
        single = find_fixed_point(compass, p.state, params={"slope": p.value})
        assert np.max(np.abs(single.fixed_point - p.state)) < 1e-9
        assert p.step_times[0] == pytest.approx(single.step_time, rel=1e-10)


@functools.lru_cache(maxsize=1)
def _oracle_flip() -> float:
    from oracles.compass_gait import first_period_doubling

    return first_period_doubling()


def test_flip_agrees_with_the_period_two_orbits_found_by_brute_force(compass, flip_branch):
    (flip,) = flip_branch.flips()
    assert flip_branch.folds() == []
    # brute force: iterate the map past the flip onto the period-2 attractor, solve its period-2
    # orbits on a few slopes beyond; a supercritical flip's orbits split as |x₁ − x₂|² ∝ γ − γ*
    # (normal form), so the root of a cubic fit of the squared split is the doubling point
    lc = find_fixed_point(compass, params={"slope": 0.0772})
    x = poincare_iterates(compass, lc.fixed_point + [1e-3, -1e-3, 0, 0], params={"slope": 0.0772}, steps=600)[-1]
    slopes = (0.07665 + 1e-4 * np.arange(1, 7))[::-1]
    split2 = []
    for s in slopes:
        orbit = find_fixed_point(compass, x, params={"slope": s}, period=2)
        assert orbit.period == 2
        x = orbit.fixed_point
        split2.append(float(np.sum((orbit.orbit[0] - orbit.orbit[1]) ** 2)))
    roots = np.roots(np.polyfit(slopes - 0.0766, split2, 3)).real + 0.0766
    brute = roots[np.argmin(np.abs(roots - flip.value))]
    assert abs(flip.value - brute) < 1e-8
    # the first period doubling of the compass gait: Goswami, Thuilot & Espiau print 4.37°; their
    # equations re-integrated by SciPy (tests/oracles/compass_gait.py, DOP853 1e-12, Newton on the
    # section map, brentq on det(J + I) to 1e-7 rad) put it at 4.3909°. The printed value is
    # 0.021° lower, within 0.03° (the printed figure's precision, see docs/references.md)
    assert math.degrees(flip.value) == pytest.approx(4.37, abs=0.03)
    assert flip.value == pytest.approx(_oracle_flip(), abs=1e-6)


def test_multiplier_at_the_located_flip_is_minus_one(compass, flip_branch):
    (flip,) = flip_branch.flips()
    assert np.min(np.abs(flip.point.multipliers + 1)) < 1e-8
    # the fixed-point search (its own Newton and chart) at that slope agrees
    lc = find_fixed_point(compass, flip.point.state, params={"slope": flip.value})
    assert np.min(np.abs(lc.multipliers + 1)) < 1e-8
    # and central differences, to their truncation error
    assert np.min(np.abs(_fd_multipliers(compass, lc.fixed_point, {"slope": flip.value}) + 1)) < 1e-5


def test_test_functions_are_the_products_over_multipliers(compass):
    lc = find_fixed_point(compass, params={"slope": 0.05})
    fold, flip, _ = _tests(lc.jacobian)
    assert fold == pytest.approx(float(np.prod(lc.multipliers - 1).real), rel=1e-9)
    assert flip == pytest.approx(float(np.prod(lc.multipliers + 1).real), rel=1e-9)


def test_kneed_biped_fold_is_where_the_gaits_are_born(kneed):
    """Hsu Chen's walker continued down from her slope: the stable gait turns at a fold into the
    unstable one. Truth: a multiplier +1 there (central differences), the branch's lowest slope,
    and brute force: no gait just below it, two distinct gaits just above."""
    br = continue_branch(kneed, "slope", 0.0504, 0.03, params=HSU_CHEN, max_delta=3e-3)
    (fold,) = br.folds()
    lo = fold.value
    assert 0.03 < lo < 0.035
    assert np.min(br.values()) >= lo - 1e-10
    assert np.min(np.abs(fold.point.multipliers - 1)) < 1e-8
    fd = _fd_multipliers(kneed, fold.point.state, {**HSU_CHEN, "slope": lo})
    assert np.min(np.abs(fd - 1)) < 1e-5
    # the two sides of the fold: the branch points nearest to it, one stable and one not
    above = {**HSU_CHEN, "slope": lo + 2e-4}
    near = sorted(br.points, key=lambda p: abs(p.value - lo - 2e-4))
    gaits = []
    for p in near[:6]:
        try:
            gaits.append(find_fixed_point(kneed, p.state, params=above).fixed_point)
        except ConvergenceError:
            pass
    assert max(np.max(np.abs(a - b)) for a in gaits for b in gaits) > 1e-3  # two different gaits
    with pytest.raises(ConvergenceError):
        find_fixed_point(kneed, fold.point.state, params={**HSU_CHEN, "slope": lo - 2e-4})


def test_kneed_biped_stays_on_the_stable_gait(kneed):
    """From Hsu Chen's slope 0.0504 to 0.06 the branch stays on the stable gait (step ≈ 0.575 s),
    not the unstable one (0.474 s, |μ| 3.60) that a search from the default guess finds."""
    br = continue_branch(kneed, "slope", 0.0504, 0.06, params=HSU_CHEN, max_delta=2e-3)
    assert br.points[-1].value == pytest.approx(0.06, abs=1e-14)
    assert all(p.stable for p in br.points)
    end = br.points[-1]
    assert end.step_times[0] == pytest.approx(0.575, abs=0.002)
    assert end.max_modulus < 1


def test_cascade_switches_onto_the_period_two_branch(compass):
    one, two = cascade(compass, "slope", 0.074, 0.08, levels=2)
    (flip,) = one.flips()
    assert two.period == 2 and two.points[0].value >= flip.value - 1e-9
    for p in two.points:
        assert p.residual < 1e-10
    end = two.points[-1]
    # a true period-2 orbit: two different footfalls, each mapped onto the other (one step of the map)
    P = ReturnMap(compass, {"slope": end.value})
    assert np.max(np.abs(end.orbit[0] - end.orbit[1])) > 1e-2
    assert np.max(np.abs(P(end.orbit[0])[0] - end.orbit[1])) < 1e-9
    assert np.max(np.abs(P(end.orbit[1])[0] - end.orbit[0])) < 1e-9
    assert end.step_times[0] != pytest.approx(end.step_times[1], abs=1e-3)
    # the period-2 gait is stable past the flip (a supercritical doubling)
    assert two.points[len(two.points) // 2].stable


def test_cli_continuation(tmp_path, capsys):
    out, plot = tmp_path / "c.csv", tmp_path / "c.png"
    rc = main(["sweep", "compass-gait", "--kind", "continuation", "--param", "slope=0.074:0.08:10", "--out", str(out),
               "--plot", str(plot), "--json"])
    assert rc == 0
    js = json.loads(capsys.readouterr().out)
    flips = [b for b in js["bifurcations"] if b["kind"] == "flip"]
    assert flips and flips[0]["slope"] == pytest.approx(_oracle_flip(), abs=1e-6)
    assert [b["period"] for b in js["branches"]] == [1, 2, 4][: len(js["branches"])] and len(js["branches"]) >= 2
    head = out.read_text().splitlines()[0].split(",")
    assert head[:4] == ["branch", "row", "i", "slope"] and "stable" in head and "multipliers" in head
    assert plot.stat().st_size > 1000
    for bad in (["--param", "slope=0.07"], ["--param", "slope=0.07:0.07"],
                ["--param", "slope=0.07:0.08", "--param", "mh=9:10"]):
        assert main(["sweep", "compass-gait", "--kind", "continuation", *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Traceback" not in err
