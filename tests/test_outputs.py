"""Outputs: CSV event markers, the basin file's axis columns named after the coordinates (an old
file refused), the ``amble models`` text, the sweep example and its progress bar when piped."""

from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np
import pytest

import amble
from amble.analysis.poincare import find_fixed_point
from amble.analysis.sweep import sweep
from amble.cli.main import build_parser, main
from amble.errors import OutputError

SYNC = {"scheduler": "synchronous", "progress": False}


def test_csv_marks_the_pre_and_post_rows_of_each_event(compass, tmp_path):
    tr = amble.simulate(compass, steps=3)
    rows = list(csv.DictReader(tr.save(tmp_path / "w.csv").open()))
    marked = [(k, r) for k, r in enumerate(rows) if r["event"]]
    assert [r["event"] for _, r in marked] == ["heel_strike:pre", "heel_strike:post"] * 3
    for (k0, pre), (k1, post) in zip(marked[::2], marked[1::2]):
        assert k1 == k0 + 1 and pre["t [s]"] == post["t [s]"]
        # the legs swap at heel strike: the new stance angle is the old swing angle
        assert float(post["stance [rad]"]) == pytest.approx(float(pre["swing [rad]"]), abs=1e-12)
    assert [float(marked[k][1]["t [s]"]) for k in (0, 2, 4)] == pytest.approx([e.t for e in tr.events])


def test_basin_axis_columns_are_the_coordinates_and_an_old_file_is_refused(compass, tmp_path):
    xs = find_fixed_point(compass).fixed_point
    over = {"stance": np.linspace(xs[0] - 0.05, xs[0] + 0.05, 2),
            "stance_dot": np.linspace(xs[2] - 0.1, xs[2] + 0.1, 2)}
    res = sweep(compass, "basin", over, steps=10, out=tmp_path / "basin.csv", **SYNC)
    header = next(csv.reader((tmp_path / "basin.csv").open()))
    assert header[:4] == ["i", "j", "stance", "stance_dot"] and "a" not in header
    assert sum(res.counts().values()) == 4
    old = tmp_path / "old.csv"
    old.write_text("i,j,a,b,outcome,reason,steps,distance\n0,0,-0.27,0.99,converged,,10,1e-05\n", encoding="utf-8")
    with pytest.raises(OutputError, match="different kind of sweep"):
        sweep(compass, "basin", over, steps=10, out=old, **SYNC)
    # a coordinate named twice is one entry of the grid: refused, a basin needs two
    with pytest.raises(amble.StateError, match="takes 2 entries"):
        sweep(compass, "basin", dict(zip(("stance", "stance"), over.values())), **SYNC)


def test_models_text_is_tidy(capsys):
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    assert "``" not in out and ":class:" not in out
    wheel = next(line for line in out.splitlines() if line.startswith("rimless-wheel"))
    assert " 1 coordinate " in wheel and "1 coordinates" not in out
    assert "pelvis of width w," in out


def test_sweep_example_names_a_branch_plot():
    sub = next(a for a in build_parser()._actions if getattr(a, "choices", None) and "sweep" in a.choices)
    epilog = sub.choices["sweep"].epilog
    assert "--plot branch.png" in epilog and "bifurcation.png" not in epilog


def test_sweep_progress_bar_ends_its_line_when_piped(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "amble.cli", "sweep", "compass-gait", "--param", "slope=0.04:0.05:2",
                           "--scheduler", "synchronous"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          timeout=300, cwd=tmp_path)  # bytes: a carriage return must stay one
    out = proc.stdout.decode()
    assert proc.returncode == 0, out
    assert "fixed-point:" in out  # the bar was drawn, and the summary starts a line of its own
    assert "\ncompass-gait: fixed-point sweep" in out and "\rcompass-gait" not in out, repr(out)
