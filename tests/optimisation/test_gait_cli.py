"""``amble optimize-gait``: the gait.json contract, one-line errors with exit 2, solver failures
with exit 1 and no traceback, progress on stderr."""

import json

import numpy as np
import pytest

pytest.importorskip("casadi")

from amble.analysis.poincare import find_fixed_point  # noqa: E402
from amble.cli.main import main  # noqa: E402
from amble.models import load  # noqa: E402

ACTUATED = '''
from amble.models import compass_gait


def build():
    s = compass_gait.build()
    m = s.modes["compass-gait"]
    st, sw = m.q
    m.actuator("hip", on=sw - st, limit=40.0)
    m.actuator("ankle", on=st, limit=20.0)
    return s
'''


def run(capsys, *args):
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_gait_json_contract_and_the_passive_fixed_point(capfd, tmp_path):
    """(capfd: the solver prints from C, so its progress is seen on file descriptor 2.)"""
    path = tmp_path / "gait.json"
    code, out, err = run(capfd, "optimize-gait", "compass-gait", "--set", "slope=0.0524", "--out", str(path), "--json")
    assert code == 0, err
    d = json.loads(path.read_text())
    assert {"objective", "fixed_point", "step_time", "trajectory", "constraints", "state_names"} <= set(d)
    assert d["state_names"] == ["stance", "swing", "stance_dot", "swing_dot"]
    lc = find_fixed_point(load("compass-gait"), params={"slope": 0.0524})
    assert np.abs(np.array(d["fixed_point"]) - lc.fixed_point).max() <= 1e-6
    assert d["max_violation"] <= 1e-8 and len(d["trajectory"]["t"]) == 61
    assert "iter" in err and "objective" in err  # solver progress went to stderr, stdout is the JSON
    assert json.loads(out)["fixed_point"] == d["fixed_point"]  # nothing but the JSON on stdout


@pytest.mark.parametrize("args, match", [
    (["--speed", "-1"], "--speed must be positive"),
    (["--speed", "1", "--step-length", "0.5"], "not allowed with"),
    (["--nodes", "1"], "--nodes"),
    (["--nodes", "20,x"], "--nodes"),
    (["--objective", "foo*2"], "foo"),
    (["--bound", "knee=0:1"], "knee"),
    (["--speed", "1.0"], "over-determined"),
    (["--out", "gait.csv"], ".json"),
])
def test_bad_input_is_one_line_and_exit_2(capsys, args, match):
    code, _, err = run(capsys, "optimize-gait", "compass-gait", "--quiet", *args)
    assert code == 2
    assert match in err and len(err.strip().splitlines()) == 1


def test_solver_failure_names_the_reason_exit_1(capsys, tmp_path):
    model = tmp_path / "actuated.py"
    model.write_text(ACTUATED)
    code, out, err = run(capsys, "optimize-gait", str(model), "--set", "slope=0", "--speed", "0.8", "--guess", "stand",
                         "--nodes", "10", "--max-iter", "2", "--quiet", "--json")
    assert code == 1
    assert "iteration limit" in err and "most violated" in err and "Traceback" not in err
    assert json.loads(out)["type"] == "SolverError"


def test_posture_has_the_models_coordinate_count(capsys, tmp_path):
    code, _, err = run(capsys, "optimize-gait", "rabbit", "--guess", "stand", "--posture", "0,1",
                       "--out", str(tmp_path / "g.json"))
    assert code == 2 and "posture must be 5 finite numbers" in err and "Traceback" not in err


def test_rabbit_at_0_8_m_per_s_from_the_command_line(capfd, tmp_path):
    """``optimize-gait`` on the library RABBIT with its naive default start (standing still)
    and, by default, its own virtual constraints: 0.8 m/s, feasible, the parameters for its
    controller in gait.json."""
    path = tmp_path / "gait.json"
    code, out, err = run(capfd, "optimize-gait", "rabbit", "--speed", "0.8", "--out", str(path), "--quiet")
    assert code == 0, err
    d = json.loads(path.read_text())
    assert d["speed"] == pytest.approx(0.8, rel=1e-9) and d["max_violation"] <= 1e-8
    assert set(d["bezier"]["params"]) >= {"alpha_0_0", "alpha_3_5", "phase_start", "phase_end"}


def test_two_step_gait_from_the_command_line(capsys, tmp_path):
    """``--steps 2`` on the passive compass gait at 4.6° (past its first period doubling): both
    steps in gait.json, the pair the period-2 orbit of the exact return map; a bad count exits 2."""
    path = tmp_path / "gait.json"
    code, out, err = run(capsys, "optimize-gait", "compass-gait", "--set", "slope=0.0803", "--steps", "2",
                         "--nodes", "20,60", "--quiet", "--out", str(path))
    assert code == 0, err
    assert "step 2:" in out
    d = json.loads(path.read_text())
    assert d["period"] == 2 and len(d["steps"]) == 2
    lc = find_fixed_point(load("compass-gait"), d["fixed_point"], params={"slope": 0.0803}, period=2)
    assert lc.period == 2
    assert np.abs(np.asarray(lc.orbit[1]) - d["steps"][1]["fixed_point"]).max() <= 1e-6
    code, _, err = run(capsys, "optimize-gait", "compass-gait", "--steps", "0")
    assert code == 2 and "--steps" in err and "Traceback" not in err
