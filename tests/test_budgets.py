"""Runs are bounded in memory and time: finite spans, a recording budget, events-only summaries."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import amble
from amble import StateError
from amble.models import load


@pytest.mark.parametrize("kw", [{"t_end": math.inf}, {"t_end": 1e308 * 10}, {"sample_dt": -0.01},
                                {"sample_dt": math.nan}])
def test_unbounded_spans_and_bad_sampling_are_refused(kw):
    with pytest.raises(StateError):
        amble.simulate(load("compass-gait"), **({"steps": 1} | kw))


def test_recording_stops_at_its_budget_with_what_it_has():
    # a fine grid over a long run once took the machine's memory; now it ends, named, at the budget
    tr = amble.simulate(load("compass-gait"), steps=50, sample_dt=1e-5, budget=2 * 2**20)
    assert tr.status == "record_limit" and "sample_dt" in tr.message
    assert 0 < tr.t[-1] < 50 * 0.74 and tr.x.nbytes <= 2 * 2**20
    assert np.all(np.diff(tr.t) >= 0)


def test_events_only_keeps_footfalls_and_the_ends():
    full = amble.simulate(load("compass-gait"), steps=20)
    lean = amble.simulate(load("compass-gait"), steps=20, samples=False)
    assert lean.status == full.status == "completed" and len(lean.t) == 2
    np.testing.assert_array_equal(lean.final_post_impact_state, full.final_post_impact_state)
    assert [e.t for e in lean.events] == [e.t for e in full.events]


def test_every_walker_has_a_step_time_limit():
    # a kneed walker put down at rest once recorded until memory ran out
    tr = amble.simulate(load("kneed-biped"), [0.0] * 6, steps=1, samples=False)
    assert tr.status == "fell" and tr.t[-1] <= 5.0 + 1e-9


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the peak memory from /proc")
def test_a_long_summary_run_uses_little_memory():
    # peak resident memory of the process itself (VmHWM of its own address space; ru_maxrss would
    # also count the pages of the forking test process)
    code = ("import json, sys; from amble.cli.main import main; "
            "rc = main(['simulate', 'compass-gait', '--steps', '100000', '--json']); "
            "hwm = [ln for ln in open('/proc/self/status') if ln.startswith('VmHWM')][0].split()[1]; "
            "print(json.dumps({'rc': rc, 'kib': int(hwm)}), file=sys.stderr)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    out = json.loads(r.stdout)
    stats = json.loads(r.stderr.strip().splitlines()[-1])
    assert stats["rc"] == 0 and out["status"] == "completed" and out["steps"] == 100000
    assert stats["kib"] < 200 * 1024, f"peak memory {stats['kib'] / 1024:.0f} MiB"  # was 1.38 GB


@pytest.mark.parametrize("args", [["limit-cycle", "compass-gait", "--rtol", "0"],
                                  ["limit-cycle", "compass-gait", "--rtol", "1", "--atol", "1"],
                                  ["simulate", "compass-gait", "--rtol", "10", "--atol", "10"],
                                  ["sweep", "compass-gait", "--param", "slope=0.04:0.05:2", "--rtol", "1e-300",
                                   "--scheduler", "synchronous"]])
def test_tolerances_outside_their_domain_are_refused(args, capsys):
    from amble.cli.main import main

    assert main(args) == 2  # --rtol 1e-300 once hung; --rtol 1 ended in an IndexError
    assert "must be a number in [1e-16, 1)" in capsys.readouterr().err


def test_an_npz_suffix_in_capitals_is_written_where_asked(tmp_path):
    out = tmp_path / "up.NPZ"
    amble.simulate(load("compass-gait"), steps=1).save(out)
    assert out.stat().st_size > 0 and not (tmp_path / "up.NPZ.npz").exists()  # was: empty up.NPZ + up.NPZ.npz
    assert {"t", "stance", "event_t"} <= set(np.load(out).files)


def test_an_empty_field_in_x0_is_an_error_not_dropped(capsys):
    from amble.cli.main import main

    assert main(["simulate", "compass-gait", "--steps", "1", "--start", "x0=-0.2,,0.3,1,0.3"]) == 2
    assert "empty value at position 2" in capsys.readouterr().err
