"""Basin rows written a block at a time: the text of every cell is what formatting each value
alone writes, and reads back as the same double; each stored cell is what a direct walk of its
initial state gives (a Python loop over ``engine.run``, independent of the batched walks); a
basin resumed on two threads, after a torn write, equals an uninterrupted one on one thread byte
for byte; and rows of finished tasks stay in the file when a later task fails.
"""

from __future__ import annotations

import csv
import math
import struct
import time

import numpy as np
import pytest
from cells import walk_cell

from amble import sweep
from amble.analysis.basin import BASIN_LABELS
from amble.analysis.cells import TextRows, fmt_floats, fmt_ints, fmt_value
from amble.analysis.defaults import BASIN_TOL
from amble.analysis.poincare import find_fixed_point
from amble.analysis.store import ResultStore
from amble.backend.kernels import compiled
from amble.errors import ConvergenceError, OutputError
from amble.simulation.engine import Options

SYNC = {"scheduler": "synchronous", "progress": False}
SLOPE = 0.05  # the compass gait's default


def _bits(x: float) -> int:
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def test_columns_formatted_at_once_as_one_value_at_a_time():
    rng = np.random.default_rng(7)
    # random bit patterns (every exponent, subnormals, NaNs with payloads) and the awkward values
    raw = rng.integers(0, 2**63, size=2000, dtype=np.int64).view(float)
    tricky = [0.0, -0.0, 0.1, 1 / 3, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, math.inf,
              -math.inf, math.nan, 1e16, 123456789012345678.0, -0.35, np.float64(0.7)]
    vals = [*raw.tolist(), *tricky]
    text = fmt_floats(vals)
    assert text == [fmt_value(float(v)) for v in vals]
    for v, t in zip(vals, text):
        back = float(t)
        assert _bits(back) == _bits(float(v)) or (math.isnan(v) and math.isnan(back))
    ints = [0, -1, 7, 2**62, -(2**62), np.int64(5), np.int32(-3)]
    assert fmt_ints(ints) == [fmt_value(v) for v in ints] == ["0", "-1", "7", str(2**62), str(-(2**62)), "5", "-3"]


def test_text_rows_append_as_dict_rows(tmp_path):
    cols = {"i": "int", "x": "float", "reason": "str"}
    rows = [{"i": 0, "x": 0.1, "reason": ""}, {"i": 1, "x": math.nan, "reason": "fell, then rolled"},
            {"i": 0, "x": 9.0, "reason": "a second row of key 0: not written"}]
    with ResultStore(tmp_path / "a.csv", cols, ["i"]) as a:
        a.append(rows)
    with ResultStore(tmp_path / "b.csv", cols, ["i"]) as b:
        b.append(TextRows([("0", fmt_value(0.1), "")]))
        b.append(TextRows([("1", "nan", "fell, then rolled"), ("0", "9.0", "not written")]))
        assert b.rows[("0",)] == {"i": "0", "x": "0.1", "reason": ""}
        with pytest.raises(ValueError, match="3 columns"):
            b.append(TextRows([("2", "0.5")]))
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert b"\"fell, then rolled\"" in (tmp_path / "b.csv").read_bytes()  # quoted as csv does


@pytest.fixture(scope="module")
def walker(compass):
    k = compiled(compass)
    p = np.array(k.meta["param_defaults"], float)
    return k, p, find_fixed_point(compass).fixed_point


def _on_slope(a: float, b: float, base: np.ndarray) -> np.ndarray:
    """Both feet on the slope (the compass gait's post-impact section); the swing velocity of
    the base state. Cells with stance > −0.12 are made invalid, stance < −0.38 are off the section."""
    if a < -0.38:
        raise ConvergenceError("off the section, by this test's fiat")
    x = base.copy()
    x[0], x[1], x[2] = a, 2 * SLOPE - a, b
    if a > -0.12:
        x[3] = math.nan
    return x


def test_basin_cells_written_are_direct_walks(compass, walker, tmp_path):
    k, p, xs = walker
    steps, every, tol = 20, 5, 1e-6
    out = tmp_path / "basin.csv"
    av, bv = np.linspace(xs[0] - 0.18, xs[0] + 0.18, 7), np.linspace(xs[2] - 0.3, xs[2] + 0.3, 5)  # x* a node
    res = sweep(compass, "basin", {"stance": av, "stance_dot": bv}, to_state=_on_slope, steps=steps,
                check_every=every, tol=tol, rows_per_task=3, threads=2, out=out, **SYNC)
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 35
    opts = Options(rtol=BASIN_TOL, atol=BASIN_TOL, max_step_time=compass.max_step_time)
    seen = set()
    for r in rows:
        i, j = int(r["i"]), int(r["j"])
        a, b = av[i], bv[j]
        assert (r["stance"], r["stance_dot"]) == (repr(float(a)), repr(float(b)))
        if a < -0.38:
            want = ("failed", "off the section", 0, math.nan)
        elif a > -0.12:
            want = ("failed", "invalid initial state", 0, math.nan)
        else:
            want = walk_cell(k, p, _on_slope(a, b, xs), xs, opts, steps, every, tol)
        got = (r["outcome"], r["reason"], int(r["steps"]), float(r["distance"]))
        assert got[:3] == want[:3], (i, j)
        assert _bits(got[3]) == _bits(want[3]) or (math.isnan(got[3]) and math.isnan(want[3])), (i, j)
        assert BASIN_LABELS[res.outcome[i, j]] == got[0] and res.steps[i, j] == got[2]
        seen.add(got[0])
    assert {"converged", "fell", "not converged", "failed"} <= seen  # every kind of cell was checked


def test_resumed_basin_on_two_threads_equals_uninterrupted_one(compass, walker, tmp_path):
    _, _, xs = walker
    grid = {"stance": np.linspace(xs[0] - 0.12, xs[0] + 0.08, 7),
            "stance_dot": np.linspace(xs[2] - 0.4, xs[2] + 0.3, 6)}
    kw = dict(steps=30, rows_per_task=2, **SYNC)
    ref = tmp_path / "ref.csv"
    full = sweep(compass, "basin", grid, out=ref, **kw)
    assert full.computed == 42 and len(set(full.outcome.ravel().tolist())) >= 2
    part = tmp_path / "part.csv"
    first = sweep(compass, "basin", grid, out=part, max_points=18, threads=2, **kw)
    assert first.computed == 18 and int(np.sum(first.outcome >= 0)) == 18
    with open(part, newline="") as f:
        assert sum(1 for _ in f) == 1 + 18  # durable rows (in the journal) as soon as tasks end
    with open(part, "a") as f:  # a write torn by a kill: a partial last line without newline
        f.write("3,0,-0.3,0.9,conv")
    second = sweep(compass, "basin", grid, out=part, threads=2, **kw)
    assert second.computed == 42 - 18
    assert part.read_bytes() == ref.read_bytes()
    for name in ("outcome", "steps", "distance", "reasons"):
        np.testing.assert_array_equal(getattr(second, name), getattr(full, name))


@pytest.mark.parametrize("threads", [1, 2])
def test_rows_of_finished_tasks_stay_when_a_later_task_fails(compass, tmp_path, threads):
    """On two threads, tasks run side by side: a failing task drops the tasks not started, but
    the one still running is finished and its rows are kept."""

    def to_state(a, b, base):
        if abs(a + 0.25) < 1e-9 and b == 0.9:
            time.sleep(0.3)  # row 1 is still running when row 2 (started after row 0) fails
        if a > -0.22:
            raise OutputError("a user's embedding that fails on the later rows")
        return _on_slope(a, b, base)

    out = tmp_path / "basin.csv"
    grid = {"stance": np.linspace(-0.3, -0.1, 5), "stance_dot": np.linspace(0.9, 1.3, 4)}
    with pytest.raises(OutputError, match="later rows"):
        sweep(compass, "basin", grid, to_state=to_state, steps=10, rows_per_task=1, out=out, threads=threads, **SYNC)
    with open(out, newline="") as f:
        done = sorted((int(r["i"]), int(r["j"])) for r in csv.DictReader(f))
    assert done == [(i, j) for i in range(2) for j in range(4)]  # stance −0.3 and −0.25: rows 0 and 1
    again = sweep(compass, "basin", grid, to_state=_on_slope, steps=10, rows_per_task=1, out=out, **SYNC)
    assert again.computed == 12  # the finished rows are not walked again
