"""``amble doublings``: the compass gait's cascade from the command line, against the flip an
independent SciPy implementation locates (tests/oracles/compass_gait.py, det(J + I) = 0), and
bad input refused with exit code 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from amble.cli.main import main


def test_cascade_from_the_command_line(capsys, tmp_path):
    from oracles.compass_gait import first_period_doubling

    png = tmp_path / "cascade.png"
    assert main(["doublings", "compass-gait", "--param", "slope=0.075:0.088", "--levels", "2", "--json",
                 "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["periods"] == [1, 2] and len(out["flips"]) == 2
    assert out["flips"][0]["value"] == pytest.approx(first_period_doubling(xtol=1e-10), abs=1e-8)
    # the period-2 gait's own flip lies beyond (Goswami et al.: 4.9°, re-computed 4.914°)
    assert np.degrees(out["flips"][1]["value"]) == pytest.approx(4.914, abs=1e-3)
    assert png.stat().st_size > 10_000 and out["plot"] == str(png)


@pytest.mark.parametrize("args, needle", [
    (["--param", "slope=0.075"], "START:STOP"),
    (["--param", "slope=0.075:0.088", "--levels", "0"], "--levels"),
    (["--param", "slope=0.075:0.088", "--tol", "-1"], "--tol"),
    (["--param", "mass=1:2"], "not a parameter"),
    (["--param", "slope=0.075:0.088", "--set", "slope=0.08"], "do not also --set"),
    (["--param", "slope=0.075:0.088", "--plot", "x.gif"], "--plot"),
])
def test_bad_input_exits_2_with_one_line(capsys, args, needle):
    assert main(["doublings", "compass-gait", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and "\n" not in err
