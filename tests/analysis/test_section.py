"""The Poincaré section derived from the step guard and reset: its dimension and chart, the
projection against the walkers' closed-form geometry (both feet on the slope, knee straight after
heel strike), and basins in any model's section coordinates (humanoid-3d, whose coordinate names
once triggered a compass-gait rule that left its swing foot off the ground)."""

from __future__ import annotations

import numpy as np
import pytest

from amble.analysis.poincare import ReturnMap, find_fixed_point
from amble.analysis.section import Section, chart
from amble.analysis.sweep import sweep
from amble.errors import StateError
from amble.models import load

SYNC = {"scheduler": "synchronous", "progress": False}


@pytest.fixture(scope="module")
def compass():
    return load("compass-gait")


@pytest.mark.parametrize("slope", [0.03, 0.05, 0.08])
def test_compass_projection_puts_both_feet_on_the_slope(compass, slope):
    lc = find_fixed_point(compass, params={"slope": slope})
    sec = Section.of(ReturnMap(compass, {"slope": slope}), lc.fixed_point)
    assert sec.dimension == 3  # 4 states, one holonomic condition (the feet on the slope)
    x = lc.fixed_point + np.array([0.04, -0.03, 0.1, -0.2])
    y = sec.project(x, [0, 2, 3])  # keep stance and both velocities
    # closed form (the section geometry of the compass gait): swing = 2·slope − stance
    assert y[1] == pytest.approx(2 * slope - x[0], abs=1e-12)
    assert np.max(np.abs(y[[0, 2, 3]] - x[[0, 2, 3]])) < 1e-12
    # a state of the section is its own projection
    assert np.max(np.abs(sec.project(lc.fixed_point) - lc.fixed_point)) < 1e-12


def test_kneed_projection_straightens_the_knee():
    """After heel strike the new swing leg's knee is straight: shank = thigh = 2·slope − stance and
    shank_dot = thigh_dot (the section of the 3-link mode, reached through the 2-link mode)."""
    s = load("kneed-biped")
    lc = find_fixed_point(s)
    sec = Section.of(ReturnMap(s), lc.fixed_point)
    assert sec.dimension == 3
    x = lc.fixed_point + 0.01 * np.arange(1, 7)
    y = sec.project(x, [0, 3, 4])
    slope = 0.05
    assert y[1] == pytest.approx(2 * slope - x[0], abs=1e-12) and y[2] == pytest.approx(y[1], abs=1e-12)
    assert y[5] == pytest.approx(x[4], abs=1e-12)


def test_chart_refuses_coordinates_tied_on_the_section(compass):
    lc = find_fixed_point(compass)
    U = Section.of(ReturnMap(compass), lc.fixed_point).tangent()
    S, E = chart(U, prefer=[0, 2])
    assert {0, 2} <= set(S.tolist()) and np.allclose(E[S, :], np.eye(len(S)))
    with pytest.raises(StateError):
        chart(U, prefer=[0, 1])  # stance and swing: tied by the feet on the slope
    with pytest.raises(StateError, match="tied on the section"):
        sweep(compass, "basin", {"stance": np.linspace(-0.3, -0.2, 2), "swing": np.linspace(0.2, 0.3, 2)}, **SYNC)


def test_humanoid_3d_basin_cell_at_the_fixed_point_converges():
    s = load("humanoid-3d")
    lc = find_fixed_point(s)
    xs, names = lc.fixed_point, lc.state_names
    sec = Section.of(ReturnMap(s), xs)
    assert np.max(np.abs(sec.project(xs) - xs)) < 1e-12  # the gait lies on its section
    a, b = names.index("stance"), names.index("stance_dot")
    over = {"stance": np.linspace(xs[a] - 0.01, xs[a] + 0.01, 3),
            "stance_dot": np.linspace(xs[b] - 0.05, xs[b] + 0.05, 3)}
    res = sweep(s, "basin", over, steps=30, **SYNC)
    assert res.outcome[1, 1] == 0  # converged, at the fixed point itself
    # every cell was put on the section and walked; a walk may end in a terminal outcome of the
    # model (the knee-swing foot scuffing the ground), never for want of a section state
    assert not {"off the section", "invalid initial state"} & set(res.reasons.ravel())


@pytest.mark.parametrize("n", [pytest.param(9, id="9x9"), pytest.param(50, id="50x50", marks=pytest.mark.slow)])
def test_humanoid_3d_yaw_basin_completes(tmp_path, n):
    """Every cell of the box is walked to an outcome, none fails; with n odd the centre cell is the
    fixed point itself and converges."""
    s = load("humanoid-3d-yaw")  # the model this basin was measured on
    xs = find_fixed_point(s).fixed_point
    over = {"stance": np.linspace(xs[0] - 0.05, xs[0] + 0.05, n),
            "stance_dot": np.linspace(xs[7] - 0.3, xs[7] + 0.3, n)}
    res = sweep(s, "basin", over, steps=30, out=tmp_path / "b.csv", **SYNC)
    c = res.counts()
    assert sum(c.values()) == n * n and c["failed"] == 0
    assert c["converged"] > n * n // 25
    if n % 2:
        assert res.outcome[n // 2, n // 2] == 0  # converged


def test_analysis_knows_no_coordinate_or_parameter_names():
    """The section comes from guards and resets: no module of the analysis layer names a walker's
    coordinate or parameter (the removed rule keyed on ``stance``, ``swing`` and ``slope``)."""
    import re
    from pathlib import Path

    import amble.analysis as pkg

    for f in Path(pkg.__file__).parent.glob("*.py"):
        code = f.read_text(encoding="utf-8")
        assert not re.search(r"""["'](slope|stance|swing)(_dot)?["']""", code), f.name
    assert not hasattr(__import__("amble.analysis.bifurcation", fromlist=["x"]), "on_section")
    assert not hasattr(__import__("amble.analysis.basin", fromlist=["x"]), "SetCoordinates")


def test_project_many_solves_the_section_equations_as_project_does():
    """The compiled Newton iteration over many states: each result lies on the section (its
    guard at the pre-impact state is zero, its coordinates S are the given ones) and is the
    state the Python iteration finds, to the projection tolerance (None exactly where project
    raises)."""
    import numpy as np

    from amble.analysis.poincare import ReturnMap, find_fixed_point
    from amble.analysis.section import Section
    from amble.errors import ConvergenceError
    from amble.models import load

    system = load("compass-gait")
    xs = find_fixed_point(system).fixed_point
    sec = Section.of(ReturnMap(system, None, rtol=1e-8, atol=1e-8), xs)
    S = sec.coordinates(prefer=[0, 2])
    rng = np.random.default_rng(5)
    X = np.tile(xs, (30, 1))
    X[:, 0] += rng.uniform(-0.2, 0.2, 30)
    X[:, 2] += rng.uniform(-0.8, 0.8, 30)
    many = sec.project_many(X, S, threads=2)
    for x, y in zip(X, many):
        try:
            ref = sec.project(x, S)
        except ConvergenceError:
            assert y is None
            continue
        assert y is not None
        np.testing.assert_allclose(y[S], x[S], atol=1e-11)
        np.testing.assert_allclose(y, ref, atol=1e-10)
    assert sum(y is not None for y in many) >= 25
