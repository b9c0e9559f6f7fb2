"""The one sweep entry point: every kind through ``amble.sweep`` gives the rows of the function it
replaces; the old names still work and warn, naming the new one; and the one period-doubling
detector, against the compass gait's flip computed independently (tests/oracles/compass_gait.py)."""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest

import amble
from amble import period_doubling, sweep
from amble.analysis.basin import basin
from amble.analysis.bifurcation import bifurcation, first_period_doubling_iterates
from amble.analysis.continuation_sweep import sweep_continuation
from amble.analysis.fixed_points import sweep_fixed_points, sweep_fixed_points_2d
from amble.analysis.sweep import KINDS
from amble.errors import StateError

SYNC = {"scheduler": "synchronous", "progress": False}
SLOPES = [0.04, 0.05, 0.06]


def _old(fn, *args, **kw):
    """An old entry point's result, and the one DeprecationWarning it gave."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = fn(*args, **kw)
    dep = [w for w in caught if issubclass(w.category, DeprecationWarning)]
    assert len(dep) == 1, [str(w.message) for w in caught]
    return res, str(dep[0].message)


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_kind_through_the_one_entry_point_gives_the_old_rows(compass, kind, tmp_path):
    if kind == "fixed-point":
        new = sweep(compass, kind, {"slope": SLOPES}, chunk=2, out=tmp_path / "new.csv", **SYNC)
        old, msg = _old(sweep_fixed_points, compass, "slope", SLOPES, chunk=2, out=tmp_path / "old.csv", **SYNC)
        new2 = sweep(compass, kind, {"slope": [0.04, 0.05], "mh": [9.0, 10.0]}, **SYNC)
        old2, _ = _old(sweep_fixed_points_2d, compass, ("slope", "mh"), ([0.04, 0.05], [9.0, 10.0]), **SYNC)
        assert new2.kind == old2.kind == "fixed-point-map" and new2.rows == old2.rows and len(new2.rows) == 4
    elif kind == "bifurcation":
        new = sweep(compass, kind, {"slope": [0.07, 0.08]}, transient=40, keep=4, out=tmp_path / "new.csv", **SYNC)
        old, msg = _old(bifurcation, compass, "slope", [0.07, 0.08], transient=40, keep=4, out=tmp_path / "old.csv",
                        **SYNC)
    elif kind == "continuation":
        new = sweep(compass, kind, {"slope": (0.05, 0.06)}, steps=4, levels=1, out=tmp_path / "new.csv",
                    progress=False)
        old, msg = _old(sweep_continuation, compass, "slope", 0.05, 0.06, steps=4, levels=1,
                        out=tmp_path / "old.csv", progress=False)
    else:
        xs = amble.find_fixed_point(compass).fixed_point
        box = ((xs[0] - 0.02, xs[0] + 0.02), (xs[2] - 0.05, xs[2] + 0.05))
        over = {"stance": np.linspace(*box[0], 3), "stance_dot": np.linspace(*box[1], 2)}
        new = sweep(compass, kind, over, steps=10, out=tmp_path / "new.csv", **SYNC)
        old, msg = _old(basin, compass, ("stance", "stance_dot"), box, (3, 2), steps=10, out=tmp_path / "old.csv",
                        **SYNC)
        assert np.array_equal(new.outcome, old.outcome) and np.array_equal(new.a_values, old.a_values)
        assert np.array_equal(new.distance, old.distance, equal_nan=True)
    assert "amble.sweep(" in msg and f'"{kind}"' in msg  # the warning names the new call
    assert (tmp_path / "new.csv").read_bytes() == (tmp_path / "old.csv").read_bytes()  # the same rows, byte for byte
    if kind != "basin":
        assert new.rows == old.rows and new.kind == old.kind and len(new.rows) >= 2


def test_the_old_keyword_continuation_still_works_and_names_warm_start(compass):
    new = sweep(compass, "fixed-point", {"slope": SLOPES}, warm_start=False, **SYNC)
    assert [r["seeded"] for r in new.rows] == ["false"] * 3  # every point from the model's guess
    with pytest.warns(DeprecationWarning, match="warm_start="):
        old = sweep(compass, "fixed-point", {"slope": SLOPES}, continuation=False, **SYNC)
    assert old.rows == new.rows
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        legacy = sweep_fixed_points(compass, "slope", SLOPES, continuation=False, **SYNC)
    assert legacy.rows == new.rows
    assert any("warm_start=" in str(w.message) for w in caught if issubclass(w.category, DeprecationWarning))


def test_period_doubling_iterates_alias_warns_and_agrees(compass):
    res = sweep(compass, "bifurcation", {"slope": [0.07, 0.08]}, transient=300, keep=8, **SYNC)
    value, msg = _old(first_period_doubling_iterates, res)
    assert value == period_doubling(res) == 0.08 and "amble.period_doubling" in msg


def test_the_entry_point_refuses_what_a_kind_does_not_take(compass):
    with pytest.raises(StateError, match="unknown sweep kind"):
        sweep(compass, "fixed-points", {"slope": SLOPES}, **SYNC)
    with pytest.raises(StateError, match="takes no option transient"):
        sweep(compass, "fixed-point", {"slope": SLOPES}, transient=3, **SYNC)
    with pytest.raises(StateError, match="takes 2 entries"):
        sweep(compass, "basin", {"stance": [0.1]}, **SYNC)
    with pytest.raises(StateError, match="scheduler, workers and max_points do not apply"):
        sweep(compass, "continuation", {"slope": (0.05, 0.06)}, max_points=3, progress=False)
    with pytest.raises(StateError, match="chunk applies to a branch"):
        sweep(compass, "fixed-point", {"slope": [0.04], "mh": [10.0]}, chunk=3, **SYNC)
    with pytest.raises(StateError, match="two ends"):
        sweep(compass, "continuation", {"slope": (0.05, 0.06, 0.07)}, progress=False)


@functools.lru_cache(maxsize=1)
def _oracle_flip() -> float:
    from oracles.compass_gait import first_period_doubling

    return first_period_doubling()


def test_period_doubling_is_located_on_the_branch_where_the_oracle_puts_it(compass):
    # truth: Goswami, Thuilot & Espiau's compass gait re-integrated by SciPy (DOP853 1e-12, Newton on
    # the section map with central differences, brentq on det(J + I) to 1e-7 rad): 4.3909°
    truth = _oracle_flip()
    assert math.degrees(truth) == pytest.approx(4.391, abs=1e-3)
    res = sweep(compass, "fixed-point", {"slope": np.linspace(0.072, 0.080, 3)}, **SYNC)  # 4 mrad apart
    located = period_doubling(res, compass)
    assert located == pytest.approx(truth, abs=1e-6)
    # the linear interpolation from the rows alone misses it by the branch's curvature over the grid
    estimate = period_doubling(res)
    assert abs(estimate - truth) > 1e-5
    # the continuation's flip is found by the same location: the same value, to LOCATE_TOL-sized noise
    cont = sweep(compass, "continuation", {"slope": (0.074, 0.079)}, levels=1, progress=False)
    assert period_doubling(cont) == pytest.approx(located, abs=1e-9)
    # no flip inside the grid: nothing to report
    assert period_doubling(sweep(compass, "fixed-point", {"slope": SLOPES}, **SYNC), compass) is None


def test_period_doubling_refuses_a_result_without_a_branch(compass):
    res = sweep(compass, "fixed-point", {"slope": [0.04], "mh": [10.0]}, **SYNC)
    with pytest.raises(StateError, match="not 'fixed-point-map'"):
        period_doubling(res)
    xs = amble.find_fixed_point(compass).fixed_point
    cells = sweep(compass, "basin", {"stance": [xs[0]], "stance_dot": [xs[2]]}, steps=5, **SYNC)
    with pytest.raises(StateError, match="not 'BasinResult'"):
        period_doubling(cells)
