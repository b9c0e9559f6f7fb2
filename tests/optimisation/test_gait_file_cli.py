"""A designed gait as the start of `amble simulate --gait` and `amble limit-cycle --gait`: the
two-stance-mode compass gait with a hip motor, designed by `amble optimize-gait` with its own
virtual constraints, walks 20 steps in closed loop from the gait file, and its limit cycle's
multiplier is the restricted Poincaré map's over the period (the HZD theorem, Westervelt et al.
2003: one full-order multiplier equals it); bad files are one-line errors with exit code 2."""

import json
from pathlib import Path

import pytest

pytest.importorskip("casadi")

from amble.cli.main import main  # noqa: E402

MODEL = str(Path(__file__).parents[1] / "two_mode_walkers.py") + ":compass_two_modes_hzd"


def run(capfd, *args):
    code = main(list(args))
    out = capfd.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def gait_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("gait") / "gait.json"
    code = main(["optimize-gait", MODEL, "--speed", "0.6", "--nodes", "20", "--guess", "interpolate", "--step-time",
                 "0.7", "--quiet", "--out", str(path)])
    assert code == 0
    return path


def test_a_designed_two_mode_gait_walks_and_is_its_own_limit_cycle(capfd, gait_file):
    d = json.loads(gait_file.read_text())
    assert d["modes"] == ["left", "right"] and d["period"] == 2
    code, out, err = run(capfd, "simulate", MODEL, "--gait", str(gait_file), "--steps", "20", "--json")
    assert code == 0, err
    walk = json.loads(out)
    assert walk["status"] == "completed" and walk["steps"] == 20
    code, out, err = run(capfd, "limit-cycle", MODEL, "--gait", str(gait_file), "--json")
    assert code == 0, err
    lc = json.loads(out)
    assert lc["period"] == 2 and lc["stable"]
    mu = d["stability"]["restricted_multiplier"]
    assert max(abs(complex(re, im)) for re, im in lc["multipliers"]) == pytest.approx(mu, rel=1e-8)
    fixed = [float(v) for v in lc["fixed_point"].values()] if isinstance(lc["fixed_point"], dict) else lc["fixed_point"]
    assert max(abs(a - b) for a, b in zip(fixed, d["fixed_point"])) <= 2e-4  # the collocation's error


@pytest.mark.parametrize("text, message", [("{", "not a gait file"), ('{"x": 1}', "no fixed_point"),
                                           ('{"fixed_point": [0, 0, 0, 0], "state_names": ["a", "b", "c", "d"]}',
                                            "are not those of")])
def test_a_bad_gait_file_is_one_line_and_exit_2(capfd, tmp_path, text, message):
    bad = tmp_path / "bad.json"
    bad.write_text(text)
    for command in ("simulate", "limit-cycle"):
        code, out, err = run(capfd, command, "compass-gait", "--gait", str(bad))
        assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    code, out, err = run(capfd, "simulate", "compass-gait", "--gait", str(bad), "--start", "fixed-point")
    assert code == 2
