"""A basin's set-up and its tasks: the fixed point it measures cells against is a root of the
return map as SciPy finds it (walked by ``engine.run`` alone); a second basin of the same gait
reuses it, one at other parameters or of a changed system does not; each cell of a map on the
default embedding (put on the section) is what walking the cell's own state run by run gives,
whatever the number of threads and however the grid is cut into tasks.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from cells import walk_cell
from scipy.optimize import root

import amble.analysis.poincare as poincare
from amble import sweep
from amble.analysis import basin_setup
from amble.analysis.basin import BASIN_LABELS
from amble.analysis.defaults import BASIN_TOL, FIXED_POINT_TOL
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.engine import Options, run

SYNC = {"scheduler": "synchronous", "progress": False}
AXES = ("stance", "stance_dot")


def _scipy_fixed_point(system, slope: float, guess: np.ndarray) -> np.ndarray:
    """A root of x ↦ P(x) − x in the compass gait's section coordinates (stance, stance rate, swing
    rate; both feet on the slope after a footfall), the map walked by ``engine.run``, solved by
    SciPy's MINPACK hybrid method with its own difference Jacobian."""
    k = compiled(system)
    p = np.array(k.meta["param_defaults"], float)
    p[k.meta["params"].index("slope")] = slope
    opts = Options(rtol=FIXED_POINT_TOL, atol=FIXED_POINT_TOL, max_step_time=system.max_step_time)

    def state(z: np.ndarray) -> np.ndarray:
        return np.array([z[0], 2 * slope - z[0], z[1], z[2]])

    def residual(z: np.ndarray) -> np.ndarray:
        r = run(k, p, 0, state(z), steps=1, opts=opts)
        assert r.completed
        return r.x[[0, 2, 3]] - z

    sol = root(residual, guess[[0, 2, 3]], method="hybr", options={"xtol": 1e-14})
    assert sol.success and np.max(np.abs(sol.fun)) < 1e-11
    return state(sol.x)


def _grid(a: tuple[float, float], b: tuple[float, float], n: tuple[int, int]) -> dict[str, np.ndarray]:
    """The ``AXES`` grid of ``n[0]`` × ``n[1]`` evenly spaced values over the boxes ``a``, ``b``."""
    return {AXES[0]: np.linspace(*a, n[0]), AXES[1]: np.linspace(*b, n[1])}


def _tiny(system, **kw):
    return sweep(system, "basin", _grid((-0.30, -0.15), (0.9, 1.2), (2, 2)), steps=5, **SYNC, **kw)


@pytest.fixture
def searches(monkeypatch):
    """The number of fixed-point searches run (the memo's misses)."""
    count = [0]
    real = poincare.find_fixed_point

    def counted(*a, **kw):
        count[0] += 1
        return real(*a, **kw)

    monkeypatch.setattr(poincare, "find_fixed_point", counted)
    basin_setup._SETUPS.clear()
    return count


def test_basin_fixed_point_is_scipys_root_of_the_return_map():
    system = load("compass-gait")
    res = _tiny(system)
    ref = _scipy_fixed_point(system, 0.05, res.fixed_point)
    np.testing.assert_allclose(res.fixed_point, ref, rtol=0, atol=1e-10)
    other = _tiny(system, params={"slope": 0.06})
    np.testing.assert_allclose(other.fixed_point, _scipy_fixed_point(system, 0.06, other.fixed_point), rtol=0,
                               atol=1e-10)
    assert np.max(np.abs(other.fixed_point - res.fixed_point)) > 1e-3


def test_set_up_reused_only_for_the_same_system_and_parameters(searches):
    system = load("compass-gait")
    first = _tiny(system)
    assert searches[0] == 1
    first.fixed_point[:] = 0.0  # the caller's copy: the memo is not changed through it
    again = sweep(system, "basin", _grid((-0.32, -0.12), (0.8, 1.3), (3, 2)), steps=5, **SYNC)  # another box
    assert searches[0] == 1
    np.testing.assert_array_equal(again.fixed_point, _tiny(system).fixed_point)
    assert np.all(again.fixed_point != 0.0)
    steeper = _tiny(system, params={"slope": 0.06})  # other parameters: searched again
    assert searches[0] == 2
    np.testing.assert_array_equal(steeper.fixed_point, poincare.find_fixed_point(system, params={"slope": 0.06})
                                  .fixed_point)
    searches[0] = 0
    _tiny(system, params={"slope": 0.05})  # the defaults, given by name: the search's fallbacks differ
    assert searches[0] == 1
    system.fixed_point_guess = list(np.asarray(system.fixed_point_guess, float) + 1e-3)  # where the search starts
    _tiny(system)
    assert searches[0] == 2
    twin = load("compass-gait")  # an equal system, another object: its own entry
    _tiny(twin)
    assert searches[0] == 3


def test_a_failed_search_is_not_remembered(searches):
    system = load("compass-gait")
    from amble.errors import AmbleError

    system.fixed_point_guess = [0.0, 0.0, 0.0, 0.0]  # standing still: no gait from here
    system.default_start = {}
    for _ in range(2):
        with pytest.raises(AmbleError):
            _tiny(system)
    assert searches[0] >= 2


@pytest.mark.parametrize("threads", [1, 2])
def test_cells_on_the_section_are_direct_walks(compass, threads):
    """The default embedding: a cell's state has the grid's stance angle and rate, the swing rate
    of the fixed point and both feet on the slope (the compass gait's post-impact section)."""
    steps, every, tol, slope = 20, 5, 1e-6, 0.05
    av, bv = np.linspace(-0.35, -0.10, 12), np.linspace(0.8, 1.4, 5)
    res = sweep(compass, "basin", dict(zip(AXES, (av, bv))), steps=steps, check_every=every, tol=tol,
                rows_per_task=5, threads=threads, **SYNC)
    k = compiled(compass)
    p = np.array(k.meta["param_defaults"], float)
    xs = res.fixed_point
    opts = Options(rtol=BASIN_TOL, atol=BASIN_TOL, max_step_time=compass.max_step_time)
    seen = set()
    for i, a in enumerate(av):
        for j, b in enumerate(bv):
            x = np.array([a, 2 * slope - a, b, xs[3]])
            label, _, done, dist = walk_cell(k, p, x, xs, opts, steps, every, tol)
            assert (BASIN_LABELS[res.outcome[i, j]], int(res.steps[i, j])) == (label, done), (i, j)
            if math.isnan(dist):
                assert math.isnan(res.distance[i, j])
            else:  # the section's swing angle is 2·slope − stance to rounding: the walks agree closely
                assert res.distance[i, j] == pytest.approx(dist, rel=1e-5, abs=1e-9), (i, j)
            seen.add(label)
    assert {"converged", "fell", "not converged"} <= seen


def test_tasks_cut_for_threads_give_the_same_map_and_file(compass, tmp_path):
    grid = _grid((-0.35, -0.10), (0.8, 1.4), (13, 4))
    one = sweep(compass, "basin", grid, steps=20, out=tmp_path / "one.csv", **SYNC)
    for threads, rpt in ((2, 5), (2, 1), (3, 4)):
        path = tmp_path / f"t{threads}-{rpt}.csv"
        many = sweep(compass, "basin", grid, steps=20, threads=threads, rows_per_task=rpt, out=path, **SYNC)
        for name in ("outcome", "steps", "distance", "reasons"):
            np.testing.assert_array_equal(getattr(many, name), getattr(one, name))
        assert path.read_bytes() == (tmp_path / "one.csv").read_bytes()
