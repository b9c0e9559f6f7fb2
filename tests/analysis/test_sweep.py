"""Parameter sweeps: warm-started branches, period doubling, resumable result files, failures, basins, CLI.

Truth used here: the return-map fixed-point property P(x*) = x* checked by an independent
simulation, the compass gait's post-impact section constraint stance + swing = 2·slope (both
feet on the slope), the range where the compass gait's first period doubling is expected (a
real multiplier flips through −1 between slope 0.07 and 0.09 rad; Goswami, Thuilot & Espiau
1998 — to be tightened against docs/references.md once it lists the value), and byte-for-byte
equality of files from interrupted and uninterrupted runs.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from amble import simulate
from amble.analysis.poincare import find_fixed_point
from amble.analysis.sweep import BASIN_LABELS, period_doubling, poincare_iterates, sweep
from amble.cli.main import main
from amble.errors import StateError

SYNC = {"scheduler": "synchronous", "progress": False}


def _state(row, names):
    return np.array([float(row[f"x_{n}"]) for n in names])


def _box(names, ranges, n):
    """A basin's grid: ``n[k]`` evenly spaced values over ``ranges[k]`` (both ends) of ``names[k]``."""
    return {nm: np.linspace(lo, hi, c) for nm, (lo, hi), c in zip(names, ranges, n)}


def test_warm_started_branch_matches_single_fixed_points(compass):
    vals = [0.04, 0.05, 0.06]
    res = sweep(compass, "fixed-point", {"slope": vals}, **SYNC)
    assert [r["status"] for r in res.rows] == ["ok"] * 3
    assert [r["seeded"] for r in res.rows] == ["false", "true", "true"]  # warm-started after the first
    for r, s in zip(res.rows, vals):
        x = _state(r, res.state_names)
        single = find_fixed_point(compass, params={"slope": s})
        assert np.max(np.abs(x - single.fixed_point)) < 1e-8
        # both feet on the slope after impact (geometry of the section)
        assert x[0] + x[1] == pytest.approx(2 * s, abs=1e-9)
        # independent check of P(x*) = x*: one step of a recorded simulation
        tr = simulate(compass, x, params={"slope": s}, steps=1, rtol=1e-12, atol=1e-12)
        assert np.max(np.abs(tr.final_post_impact_state - x)) < 1e-8
        assert float(r["step_time"]) == pytest.approx(tr.events[-1].t, rel=1e-8)


def test_period_doubling_between_007_and_009(compass):
    res = sweep(compass, "fixed-point", {"slope": np.linspace(0.07, 0.09, 5)}, **SYNC)
    first, last = res.rows[0], res.rows[-1]
    assert first["stable"] == "true" and last["stable"] == "false"
    mults = [complex(re, im) for re, im in json.loads(last["multipliers"])]
    assert any(abs(m.imag) < 1e-9 and m.real < -1 for m in mults)  # a flip, not a fold or Neimark–Sacker
    pd = period_doubling(res)
    assert pd is not None and 0.07 < pd < 0.09


def test_bifurcation_period_two_beyond_the_flip(compass):
    res = sweep(compass, "bifurcation", {"slope": [0.07, 0.08]}, transient=300, keep=8, **SYNC)
    a, b = res.rows
    assert a["period"] == "1" and b["period"] == "2"
    it = json.loads(b["iterates"])
    assert abs(it[0] - it[1]) > 1e-3  # two distinct stance angles alternate
    # the kept state lies on the section: stance + swing = 2·slope
    x = _state(b, res.state_names)
    assert x[0] + x[1] == pytest.approx(2 * 0.08, abs=1e-9)


def test_failing_point_is_recorded_and_sweep_goes_on(compass):
    res = sweep(compass, "fixed-point", {"slope": [0.0, 0.05]}, **SYNC)  # no passive gait on level ground
    bad, good = res.rows
    assert bad["status"] == "failed" and "ConvergenceError" in bad["reason"]
    assert good["status"] == "ok"
    bif = sweep(compass, "bifurcation", {"slope": [0.05, 0.12]}, transient=50, keep=4, **SYNC)
    assert bif.rows[0]["status"] == "ok"
    assert bif.rows[1]["status"] == "failed" and "fell" in bif.rows[1]["reason"]
    assert res.counts() == {"ok": 1, "failed": 1}


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_interrupted_sweep_resumes_to_identical_file(compass, tmp_path, suffix):
    vals = np.linspace(0.03, 0.08, 7)
    full = tmp_path / f"full{suffix}"
    part = tmp_path / f"part{suffix}"
    ref = sweep(compass, "fixed-point", {"slope": vals}, chunk=4, out=full, **SYNC)
    assert ref.complete
    r1 = sweep(compass, "fixed-point", {"slope": vals}, chunk=4, out=part, max_points=3, **SYNC)
    assert not r1.complete and r1.computed == 3 and len(r1.rows) == 3
    journal = part if suffix == ".csv" else part.with_name(part.name + ".journal.csv")
    with open(journal, "a") as f:  # a write torn by a kill: a partial last line without newline
        f.write("3,0,0.0566")
    r2 = sweep(compass, "fixed-point", {"slope": vals}, chunk=4, out=part, max_points=2, **SYNC)
    assert r2.reused == 3 and r2.computed == 2
    r3 = sweep(compass, "fixed-point", {"slope": vals}, chunk=4, out=part, **SYNC)
    assert r3.complete and r3.computed == 2 and r3.reused == 5
    assert part.read_bytes() == full.read_bytes()
    r4 = sweep(compass, "fixed-point", {"slope": vals}, chunk=4, out=part, **SYNC)  # nothing left to do
    assert r4.computed == 0 and len(r4.rows) == 7
    assert part.read_bytes() == full.read_bytes()


def test_file_of_another_grid_is_refused(compass, tmp_path):
    from amble.errors import OutputError

    out = tmp_path / "s.csv"
    sweep(compass, "fixed-point", {"slope": [0.04, 0.05]}, out=out, **SYNC)
    with pytest.raises(OutputError, match="another sweep"):
        sweep(compass, "fixed-point", {"slope": [0.04, 0.06]}, out=out, **SYNC)


def test_bifurcation_resume_identical(compass, tmp_path):
    vals = [0.07, 0.08, 0.085]
    kw = dict(transient=40, keep=6, chunk=3, **SYNC)
    sweep(compass, "bifurcation", {"slope": vals}, out=tmp_path / "a.csv", **kw)
    sweep(compass, "bifurcation", {"slope": vals}, out=tmp_path / "b.csv", max_points=1, **kw)
    sweep(compass, "bifurcation", {"slope": vals}, out=tmp_path / "b.csv", **kw)
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_map_2d_grid(compass):
    res = sweep(compass, "fixed-point", {"slope": [0.04, 0.05], "mh": [10.0, 12.0]}, **SYNC)
    assert len(res.rows) == 4 and res.counts()["ok"] == 4
    for r in res.rows:
        x = _state(r, res.state_names)
        assert x[0] + x[1] == pytest.approx(2 * float(r["slope"]), abs=1e-9)


def test_basin_small_grid(compass, tmp_path):
    xs = find_fixed_point(compass).fixed_point
    over = _box(("stance", "stance_dot"), ((xs[0] - 0.1, xs[0] + 0.1), (xs[2] - 0.5, xs[2] + 0.5)), (3, 3))
    res = sweep(compass, "basin", over, steps=40, out=tmp_path / "basin.csv", **SYNC)
    assert res.outcome[1, 1] == BASIN_LABELS.index("converged")  # the fixed point itself
    # stance + 0.1 rad with 0.5 rad/s less: far too slow to vault over the stance foot
    assert res.outcome[2, 0] == BASIN_LABELS.index("fell")
    assert sum(res.counts().values()) == 9
    again = sweep(compass, "basin", over, steps=40, out=tmp_path / "basin.csv", **SYNC)
    assert again.computed == 0 and np.array_equal(again.outcome, res.outcome)


def test_basin_on_two_threads_equals_one_cell_by_cell(compass):
    """Cells walked by two threads sharing each task's walks: every cell's outcome, steps and
    distance are those of one thread, exactly (a cell is walked whole by one thread)."""
    xs = find_fixed_point(compass).fixed_point
    over = _box(("stance", "stance_dot"), ((xs[0] - 0.1, xs[0] + 0.1), (xs[2] - 0.5, xs[2] + 0.5)), (3, 5))
    one = sweep(compass, "basin", over, steps=30, **SYNC)
    two = sweep(compass, "basin", over, steps=30, threads=2, **SYNC)
    assert len({int(v) for v in one.outcome.ravel()}) >= 2  # a map with more than one outcome
    np.testing.assert_array_equal(two.outcome, one.outcome)
    np.testing.assert_array_equal(two.steps, one.steps)
    np.testing.assert_array_equal(two.distance, one.distance)
    with pytest.raises(StateError, match="threads"):
        sweep(compass, "basin", over, steps=30, threads=0, **SYNC)


def test_plots(compass, tmp_path):
    from amble.viz import sweep_plots as sp

    fp = sweep(compass, "fixed-point", {"slope": [0.05, 0.085]}, **SYNC)
    assert sp.plot_branch(fp, tmp_path / "b.png").stat().st_size > 1000
    bif = sweep(compass, "bifurcation", {"slope": [0.05, 0.085]}, transient=20, keep=4, **SYNC)
    assert sp.plot_bifurcation(bif, tmp_path / "bif.svg").stat().st_size > 1000
    it = poincare_iterates(compass, params={"slope": 0.05}, steps=10)
    assert it.shape == (11, 4)
    assert sp.plot_poincare(it, tmp_path / "p.pdf", state_names=fp.state_names).stat().st_size > 1000
    from amble.errors import AmbleError

    with pytest.raises(AmbleError):
        sp.plot_branch(fp, tmp_path / "b.txt")


def test_cli_sweep(tmp_path, capsys):
    out = tmp_path / "s.csv"
    rc = main(["sweep", "compass-gait", "--param", "slope=0.07:0.09:3", "--scheduler", "synchronous",
               "--out", str(out), "--plot", str(tmp_path / "s.png"), "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert rc == 0 and summary["ok"] == 3 and summary["failed"] == 0
    assert 0.07 < summary["period_doubling"] < 0.09
    assert out.exists() and (tmp_path / "s.png").exists()
    assert main(["sweep", "compass-gait", "--param", "nope=0:1:2", "--scheduler", "synchronous"]) == 2
    assert main(["sweep", "compass-gait", "--kind", "bifurcation", "--param", "slope=0.05:0.06:2",
                 "--param", "mh=9:10:2", "--scheduler", "synchronous"]) == 2


@pytest.mark.parametrize("scheduler", [None, "dask"], ids=["local-processes", "dask"])
def test_fixed_point_sweep_on_two_workers_equals_the_serial_sweep(compass, scheduler):
    """Four slopes in two tasks of two (warm-started inside each task) on two local worker
    processes (forked, the default) or a local Dask cluster of two: every row — state, step time,
    multipliers, seeding — is the serial sweep's, digit for digit (the same point is the same
    computation wherever it runs)."""
    vals = [0.04, 0.05, 0.06, 0.07]
    serial = sweep(compass, "fixed-point", {"slope": vals}, chunk=2, **SYNC)
    dist = sweep(compass, "fixed-point", {"slope": vals}, chunk=2, workers=2, scheduler=scheduler, progress=False)
    assert [r["status"] for r in serial.rows] == ["ok"] * 4
    assert [r["seeded"] for r in serial.rows] == ["false", "true", "false", "true"]
    assert dist.rows == serial.rows


def test_a_branch_is_chunked_by_its_grid_and_equal_on_one_and_two_workers(compass):
    """The default chunks of a branch depend on its length only (24 values: three chunks of 8,
    each starting from the model's guess, so ``seeded`` is false at 0, 8 and 16) and the rows are
    the same, digit for digit, in this process and on two forked workers."""
    from amble.analysis.fixed_points import default_chunk

    assert [default_chunk(n) for n in (1, 24, 200, 2000)] == [8, 8, 13, 32]
    vals = np.linspace(0.03, 0.06, 24)
    one = sweep(compass, "fixed-point", {"slope": vals}, workers=1, progress=False)
    two = sweep(compass, "fixed-point", {"slope": vals}, workers=2, progress=False)
    assert [i for i, r in enumerate(one.rows) if r["seeded"] == "false"] == [0, 8, 16]
    assert [r["status"] for r in one.rows] == ["ok"] * 24
    assert two.rows == one.rows


def test_a_flip_between_two_chunks_is_located(compass):
    """A flip whose bracketing gaits lie in different chunks (so on different ``branch`` ids) is
    found and located where it is in one chunk; the compass gait's first period doubling lies
    between slope 0.07 and 0.09 rad (Goswami, Thuilot & Espiau 1998). Without the system, which
    would check that the branch runs through the chunk boundary, none is claimed there."""
    from amble.analysis.branch_bifurcations import bifurcations

    vals = [0.0745, 0.0760, 0.0772, 0.0785]  # the flip (≈ 0.0766) between the 2nd and 3rd values
    whole = sweep(compass, "fixed-point", {"slope": vals}, chunk=4, **SYNC)
    split = sweep(compass, "fixed-point", {"slope": vals}, chunk=2, **SYNC)
    assert split.rows[1]["branch"] != split.rows[2]["branch"]
    (ref,) = [b for b in bifurcations(whole, compass) if b.kind == "flip"]
    (flip,) = [b for b in bifurcations(split, compass) if b.kind == "flip"]
    assert 0.07 < flip.value < 0.09 and abs(flip.value - ref.value) < 1e-9
    assert [b for b in bifurcations(split) if b.kind == "flip"] == []


def test_a_basin_on_two_local_processes_equals_the_serial_basin(compass):
    xs = find_fixed_point(compass).fixed_point
    over = _box(("stance", "stance_dot"), ((xs[0] - 0.05, xs[0] + 0.05), (xs[2] - 0.2, xs[2] + 0.2)), (4, 4))
    serial = sweep(compass, "basin", over, steps=30, **SYNC)
    local = sweep(compass, "basin", over, steps=30, workers=2, progress=False, rows_per_task=1)
    assert np.array_equal(serial.outcome, local.outcome)
    assert set(serial.outcome.ravel()) != {serial.outcome.ravel()[0]}  # the box holds more than one outcome


def test_a_failing_task_on_local_processes_keeps_the_finished_rows(compass, tmp_path, monkeypatch):
    """A task that raises ends the sweep with its error; rows that landed before stay in the file."""
    import amble.analysis.fixed_points as fp

    real = fp._fp_task

    def failing(system, base, pnames, points, *rest):
        if points[0][0] >= 2:
            raise RuntimeError("task blew up")
        return real(system, base, pnames, points, *rest)

    monkeypatch.setattr(fp, "_fp_task", failing)
    out = tmp_path / "f.csv"
    with pytest.raises(RuntimeError, match="task blew up"):
        sweep(compass, "fixed-point", {"slope": [0.04, 0.05, 0.06, 0.07]}, chunk=1, workers=2, progress=False,
              out=out)
    monkeypatch.setattr(fp, "_fp_task", real)
    kept = list(csv.DictReader(out.open()))
    again = sweep(compass, "fixed-point", {"slope": [0.04, 0.05, 0.06, 0.07]}, chunk=1, **SYNC, out=out)
    assert again.reused == len(kept) and again.computed == 4 - len(kept)


@pytest.mark.slow
def test_local_cluster_matches_serial(compass, tmp_path):
    xs = find_fixed_point(compass).fixed_point
    over = _box(("stance", "stance_dot"), ((xs[0] - 0.05, xs[0] + 0.05), (xs[2] - 0.2, xs[2] + 0.2)), (6, 6))
    serial = sweep(compass, "basin", over, steps=30, **SYNC)
    dist = sweep(compass, "basin", over, steps=30, workers=2, scheduler="dask", progress=False, rows_per_task=2)
    assert np.array_equal(serial.outcome, dist.outcome)


def test_cli_basin(compass, tmp_path, capsys):
    xs = find_fixed_point(compass).fixed_point  # (stance, swing, stance_dot, swing_dot)
    out = tmp_path / "basin.csv"
    grid = ["--x", f"stance={xs[0] - 0.1}:{xs[0] + 0.1}:3", "--x", f"stance_dot={xs[2] - 0.5}:{xs[2] + 0.5}:3"]
    rc = main(["sweep", "compass-gait", "--kind", "basin", *grid, "--steps", "40", "--scheduler", "synchronous",
               "--out", str(out), "--plot", str(tmp_path / "basin.png"), "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert rc == 0 and summary["points"] == 9 and summary["complete"]
    assert sum(summary[lab] for lab in BASIN_LABELS) == 9
    rows = {(r["i"], r["j"]): r for r in csv.DictReader(out.open())}
    assert rows["1", "1"]["outcome"] == "converged"  # the fixed point itself
    assert rows["2", "0"]["outcome"] == "fell"  # 0.1 rad further back, 0.5 rad/s slower: cannot vault over
    assert (tmp_path / "basin.png").stat().st_size > 1000
    bad = [
        ["--kind", "basin", "--x", "stance=-0.3:-0.1:3"],  # one coordinate
        ["--kind", "basin", *grid, "--param", "slope=0.04:0.05:2"],  # parameters are --set in a basin
        ["--kind", "basin", "--x", "stance=-0.3:-0.1:3", "--x", "nope=0:1:3"],  # not a state coordinate
        ["--kind", "basin", "--x", "stance=-0.3:-0.1:3", "--x", "stance=0:1:3"],  # the same one twice
        ["--kind", "basin", *grid, "--steps", "0"],
        ["--kind", "basin", "--x", "stance=-0.3:-0.1", "--x", "stance_dot=1:2:3"],  # no count
        ["--param", "slope=0.04:0.05:2", "--steps", "10"],  # --steps is for basins
        ["--kind", "fixed-point"],  # no --param
    ]
    for extra in bad:
        assert main(["sweep", "compass-gait", *extra, "--scheduler", "synchronous"]) == 2, extra
    assert "--x expects" in capsys.readouterr().err
