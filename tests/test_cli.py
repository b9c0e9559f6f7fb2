"""The command-line contract: JSON fields, exit codes, one-line errors."""

import json
import subprocess
import sys

import pytest
import sympy as sp

from amble.cli.main import main


def run(capsys, *args):
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_models_json(capsys):
    code, out, _ = run(capsys, "models", "--json")
    assert code == 0
    names = [m["name"] for m in json.loads(out)["models"]]
    assert "compass-gait" in names


def test_simulate_json_contract(capsys, tmp_path):
    code, out, _ = run(capsys, "simulate", "compass-gait", "--steps", "5", "--json", "--out", str(tmp_path / "w.csv"))
    assert code == 0
    d = json.loads(out)
    assert d["status"] == "completed" and d["steps"] == 5 and d["events"] == 5
    assert d["state_names"] == ["stance", "swing", "stance_dot", "swing_dot"]
    assert len(d["final_post_impact_state"]) == 4
    assert (tmp_path / "w.csv").exists()


def test_limit_cycle_json_contract(capsys):
    code, out, _ = run(capsys, "limit-cycle", "compass-gait", "--json")
    assert code == 0
    d = json.loads(out)
    assert {"state_names", "fixed_point", "step_time", "multipliers", "stable"} <= set(d)
    assert d["stable"] is True and all(len(m) == 2 for m in d["multipliers"])


def test_equations_json_parses_with_sympy(capsys):
    code, out, _ = run(capsys, "equations", "compass-gait", "--json")
    assert code == 0
    d = json.loads(out)
    assert d["coordinates"] == ["stance", "swing"]
    assert d["parameters"]["slope"] == 0.05
    M = sp.Matrix([[sp.sympify(e) for e in row] for row in d["mass_matrix"]])
    h = [sp.sympify(e) for e in d["bias"]]
    names = {str(s) for s in M.free_symbols} | {str(s) for e in h for s in e.free_symbols}
    assert names <= {"stance", "swing", "stance_dot", "swing_dot", "mh", "m", "a", "b", "g", "slope"}
    assert "swing_dot" in names


@pytest.mark.parametrize(
    "args, needle",
    [
        (["simulate", "no-such-model"], "unknown model"),
        (["simulate", "compass-gait", "--set", "nope=1"], "unknown parameter"),
        (["simulate", "compass-gait", "--set", "slope"], "NAME=VALUE"),
        (["simulate", "compass-gait", "--set", "slope=abc"], "not a number"),
        (["simulate", "compass-gait", "--steps", "0"], "at least 1"),
        (["simulate", "compass-gait", "--start", "x0=1,2"], "4"),
        (["simulate", "compass-gait", "--out", "/nonexistent-dir/x.csv"], "does not exist"),
        (["simulate", "compass-gait", "--out", "x.txt"], "must end with"),
        (["sweep", "compass-gait", "--param", "slope=0.1:0.1:5"], "empty range"),
        (["bogus-command"], "invalid choice"),
    ],
)
def test_user_errors_exit_2_with_one_line(capsys, args, needle):
    code, out, err = run(capsys, *args)
    assert code == 2
    assert err.startswith("amble: error:") and err.count("\n") == 1
    assert needle in err


def test_json_error_object(capsys):
    code, out, _ = run(capsys, "simulate", "no-such-model", "--json")
    assert code == 2
    assert "unknown model" in json.loads(out)["error"]


def test_console_script_help_has_an_example():
    r = subprocess.run([sys.executable, "-m", "amble.cli", "simulate", "--help"], capture_output=True, text=True)
    assert r.returncode == 0 and "example:" in r.stdout


def test_period_two_reports_both_points_and_step_times(capsys):
    """Beyond the flip (slope 0.08) the orbit alternates two steps of different length: both
    section points and both step times are reported, not only their mean."""
    code, out, _ = run(capsys, "limit-cycle", "compass-gait", "--set", "slope=0.08", "--period", "2", "--json")
    assert code == 0
    d = json.loads(out)
    assert d["period"] == 2 and len(d["orbit"]) == 2 and len(d["step_times"]) == 2
    t1, t2 = d["step_times"]
    assert abs(t1 - t2) > 0.05 and (t1 + t2) / 2 == pytest.approx(d["step_time"], rel=1e-12)
    assert abs(d["orbit"][0][0] - d["orbit"][1][0]) > 1e-2  # two distinct stance angles
    code, out, _ = run(capsys, "limit-cycle", "compass-gait", "--set", "slope=0.08", "--period", "2")
    assert out.count("step time") == 3  # the mean, then each of the two steps


def test_period_two_search_that_finds_period_one_says_so(capsys):
    code, out, _ = run(capsys, "limit-cycle", "compass-gait", "--period", "2")
    assert code == 0 and "the period-2 search converged to a period-1 gait" in out
    code, out, _ = run(capsys, "limit-cycle", "compass-gait", "--period", "2", "--json")
    d = json.loads(out)
    assert d["period"] == 1 and d["requested_period"] == 2


def test_limit_cycle_tol_bounds_the_residual(capsys):
    # the default stops tighter than the promised 1e-10 accuracy of the fixed point; --tol loosens it
    code, out, _ = run(capsys, "limit-cycle", "round-foot-walker", "--json")
    assert code == 0 and json.loads(out)["residual"] < 1e-12
    code, out, _ = run(capsys, "limit-cycle", "round-foot-walker", "--tol", "1e-6", "--json")
    assert code == 0 and json.loads(out)["residual"] < 1e-6
    code, _, err = run(capsys, "limit-cycle", "round-foot-walker", "--tol", "0")
    assert code == 2 and "--tol" in err
    code, _, err = run(capsys, "sweep", "compass-gait", "--kind", "bifurcation", "--param", "slope=0.01:0.02:2",
                       "--tol", "1e-9")
    assert code == 2 and "--tol applies to" in err


def test_a_period_beyond_the_return_maps_bound_is_refused_before_any_work(capsys, monkeypatch):
    # one bound for the command line and the return map: refused before the model is loaded
    cli = sys.modules["amble.cli.limit_cycle"]

    def no_load(*a, **k):
        raise AssertionError("the model was loaded")

    monkeypatch.setattr(cli, "load_model", no_load)
    code, _, err = run(capsys, "limit-cycle", "compass-gait", "--period", "65")
    assert code == 2 and err.strip() == "amble: error: --period must be at least 1 and at most 64, got 65"
