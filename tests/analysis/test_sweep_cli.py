"""The sweep command line: tolerances reach the API as given (one default per setting, no silent
override), option checks create no file, typed output / scheduler errors exit 2 with one line;
typed rows of a sweep result."""

from __future__ import annotations

import inspect
import json
import math
import time

import pytest

import amble.cli.sweep as cli_sweep
from amble import OutputError, SchedulerError, sweep
from amble.analysis.defaults import BASIN_STEPS, BASIN_TOL, BIFURCATION_TOL, FIXED_POINT_TOL
from amble.analysis.poincare import find_fixed_point
from amble.analysis.store import SweepResult
from amble.analysis.sweep import KINDS
from amble.cli.args import writable_path
from amble.cli.main import main

SYNC = {"scheduler": "synchronous", "progress": False}


class _Stop(Exception):
    pass


def _capture(monkeypatch):
    """Replace the sweep entry point used by the CLI by one recording its kind and keyword arguments."""
    seen: dict = {}

    def fake(system, kind, over, **kw):
        seen.update(kw, kind=kind, over=dict(over))
        if kind == "basin":
            raise _Stop
        return SweepResult(kind=kind, params=list(over), rows=[], path=None, complete=True, computed=0, reused=0)

    monkeypatch.setattr(cli_sweep, "sweep", fake)
    return seen


def _default(fn, name):
    return inspect.signature(fn).parameters[name].default


def test_api_defaults_come_from_one_place():
    assert _default(find_fixed_point, "rtol") == _default(find_fixed_point, "atol") == FIXED_POINT_TOL
    assert KINDS["fixed-point"].tol == KINDS["continuation"].tol == FIXED_POINT_TOL
    assert KINDS["bifurcation"].tol == BIFURCATION_TOL
    assert KINDS["basin"].tol == BASIN_TOL
    assert KINDS["basin"].options()["steps"] == BASIN_STEPS
    assert _default(sweep, "rtol") is None and _default(sweep, "atol") is None  # → the kind's


@pytest.mark.parametrize("kind, grid, n", [
    ("fixed-point", ["--param", "slope=0.04:0.05:2"], 1),
    ("fixed-point", ["--param", "slope=0.04:0.05:2", "--param", "mh=9:10:2"], 2),
    ("bifurcation", ["--param", "slope=0.04:0.05:2"], 1),
    ("continuation", ["--param", "slope=0.04:0.05"], 1),
    ("basin", ["--x", "stance=-0.3:-0.2:2", "--x", "stance_dot=1:1.2:2"], 2),
])
def test_given_tolerance_is_used_and_absent_one_is_the_api_default(monkeypatch, kind, grid, n):
    seen = _capture(monkeypatch)
    argv = ["sweep", "compass-gait", "--kind", kind, *grid, "--scheduler", "synchronous", "--json"]
    assert main([*argv, "--rtol", "1e-9", "--atol", "1e-7"]) in (0, 1)
    assert seen["rtol"] == 1e-9 and seen["atol"] == 1e-7
    assert seen["kind"] == kind and len(seen["over"]) == n  # one entry point, the kind as given
    seen.clear()
    assert main(argv) in (0, 1)
    assert "rtol" not in seen and "atol" not in seen  # → the API's default of that kind
    if kind == "basin":
        assert seen["steps"] == BASIN_STEPS


def test_writable_path_creates_nothing(tmp_path):
    p = tmp_path / "r.csv"
    assert writable_path(str(p), (".csv",), "--out") == p
    assert not p.exists()
    with pytest.raises(OutputError, match="does not exist"):
        writable_path(str(tmp_path / "no" / "r.csv"), (".csv",), "--out")
    with pytest.raises(OutputError, match="must end with"):
        writable_path(str(tmp_path / "r.txt"), (".csv",), "--out")
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(OutputError, match="not a file"):
        writable_path(str(tmp_path / "d.csv"), (".csv",), "--out")


def test_refused_sweep_leaves_no_files(tmp_path):
    out, plot = tmp_path / "s.csv", tmp_path / "s.png"
    rc = main(["sweep", "compass-gait", "--param", "nope=0:1:2", "--scheduler", "synchronous", "--out", str(out),
               "--plot", str(plot)])
    assert rc == 2
    assert not out.exists() and not plot.exists()


def _one_line_error(capsys, argv, expected):
    code = main([*argv, "--json"])
    cap = capsys.readouterr()
    assert code == 2
    assert len(cap.err.strip().splitlines()) == 1 and cap.err.startswith("amble: error: ")
    assert json.loads(cap.out)["type"] == expected


def test_result_file_of_another_kind_exits_2_with_one_line(capsys, tmp_path):
    out = tmp_path / "s.csv"
    out.write_text("some,other,columns\n1,2,3\n")
    _one_line_error(capsys, ["sweep", "compass-gait", "--param", "slope=0.04:0.05:2", "--scheduler", "synchronous",
                             "--out", str(out)], "OutputError")
    assert out.read_text() == "some,other,columns\n1,2,3\n"


def test_unusable_out_path_exits_2_with_one_line(capsys, tmp_path):
    _one_line_error(capsys, ["sweep", "compass-gait", "--param", "slope=0.04:0.05:2", "--scheduler", "synchronous",
                             "--out", str(tmp_path / "missing" / "s.csv")], "OutputError")


def test_refused_scheduler_exits_2_at_once(capsys):
    t0 = time.perf_counter()
    _one_line_error(capsys, ["sweep", "compass-gait", "--param", "slope=0.04:0.05:2", "--scheduler",
                             "tcp://127.0.0.1:1"], "SchedulerError")
    assert time.perf_counter() - t0 < 5.0
    assert issubclass(SchedulerError, ConnectionError) and issubclass(OutputError, OSError)


def test_records_and_table_give_numbers(compass):
    res = sweep(compass, "fixed-point", {"slope": [0.04, 0.05]}, **SYNC)
    assert all(isinstance(v, str) for v in res.rows[0].values())  # the stored text is unchanged
    rec = res.records()[0]
    assert isinstance(rec["i"], int) and isinstance(rec["slope"], float) and rec["slope"] == 0.04
    assert isinstance(rec["stable"], bool) and isinstance(rec["step_time"], float)
    assert isinstance(rec["multipliers"], list) and rec["reason"] == ""
    tab = res.table()
    assert tab["i"].tolist() == [0, 1] and tab["slope"].dtype == float and tab["stable"].dtype == bool
    bif = sweep(compass, "bifurcation", {"slope": [0.05]}, transient=20, keep=4, **SYNC).records()[0]
    assert isinstance(bif["period"], int) and len(bif["iterates"]) == 4
    failed = SweepResult(kind="x", params=[], rows=[{"period": "", "d": ""}], path=None, complete=True, computed=0,
                         reused=0, types={"period": "int", "d": "float"})
    assert failed.records()[0]["period"] is None and math.isnan(failed.records()[0]["d"])
    assert failed.table()["period"] == [None]


def test_a_result_file_in_use_by_another_sweep_is_refused(tmp_path):
    # two sweeps on one file once both "completed", and the file held only one of them
    from amble.analysis.store import ResultStore
    from amble.errors import OutputError

    out = tmp_path / "sweep.csv"
    with ResultStore(out, ["i", "v"], ["i"]) as first:
        first.append([{"i": 0, "v": 1.0}])
        with pytest.raises(OutputError, match="in use by another sweep"):
            ResultStore(out, ["i", "v"], ["i"])
    with ResultStore(out, ["i", "v"], ["i"]) as again:  # released at the end of the first
        assert again.has(("0",))


def test_basin_threads_reach_the_api_and_do_not_change_the_cells(tmp_path):
    grid = ["--x", "stance=-0.35:-0.15:3", "--x", "stance_dot=0.9:1.3:3", "--steps", "10"]
    files = []
    for threads in ("1", "2"):
        out = tmp_path / f"b{threads}.csv"
        rc = main(["sweep", "compass-gait", "--kind", "basin", *grid, "--scheduler", "synchronous",
                   "--threads", threads, "--out", str(out), "--json"])
        assert rc == 0
        files.append(out.read_text())
    assert files[0] == files[1] and files[0].count("\n") >= 9


@pytest.mark.parametrize("extra", [["--kind", "basin", "--x", "stance=-0.3:-0.2:2", "--x", "stance_dot=1:1.2:2",
                                    "--threads", "0"],
                                   ["--param", "slope=0.04:0.05:2", "--threads", "2"]])
def test_bad_threads_exit_2_with_one_line(capsys, extra):
    _one_line_error(capsys, ["sweep", "compass-gait", *extra, "--scheduler", "synchronous"], "UsageError")
