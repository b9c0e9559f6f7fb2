"""The fixed-point search's last resort: a periodic step solved by collocation, polished by Newton
on the return map, where neither a walk at the parameters nor the model's gait followed there by
continuation finds a gait. The gait found is checked against Goswami's equations integrated with
SciPy (tests/oracles/compass_gait.py), whose own Newton must converge to it."""

import numpy as np
import pytest

from amble.analysis.collocation_guess import collocation_starts
from amble.analysis.poincare import find_fixed_point
from amble.errors import ConvergenceError
from amble.models import load

pytest.importorskip("casadi")

# a very heavy hip on short, light legs whose mass sits near the hip: the walk from the model's
# guess falls; the continuation from the default gait was lost at 99 % of the way while its
# corrector asked each point for a residual of 1e-12, which the map holds only to 2e-12 to 3e-12
# here (points along a path are now corrected to 1e-10 and the end polished by Newton)
LOST = dict(mh=80.9022, m=0.1416, a=0.0689, b=0.4301, slope=0.0205)
# light legs on a steep slope: the default gait's branch folds at slope 0.21751, just short of
# 0.2182 (with the other parameters nearly there): no gait beyond on that branch
FOLDS = dict(mh=0.9313, m=4.5418, a=0.1228, b=0.6294, slope=0.2182)
# heavy legs, a light hip: the continuation does not reach the end in its 400 steps
LONG = dict(mh=0.0478, m=26.6935, a=0.0859, b=0.721, slope=0.1063)


def _check_against_oracle(params, lc):
    from oracles import compass_gait as cg

    xa = lc.fixed_point
    # Goswami's coordinates: (th_ns, th_s) = −(swing, stance), counter-clockwise; his a is the
    # leg's mass from the foot, ours from the hip
    par = (params["m"], params["mh"], params["b"], params["a"], params.get("g", 9.81))
    x, jac = cg.fixed_point(params["slope"], np.array([-xa[0], -xa[3], -xa[2]]) + 1e-4, par)
    np.testing.assert_allclose(xa, [-x[1], -x[0], -x[3], -x[2]], rtol=0, atol=1e-9)
    # the oracle's Jacobian is by central differences (step 1e-6): its multipliers to ~1e-7
    mu = np.linalg.eigvals(jac)
    np.testing.assert_allclose(np.sort(np.abs(lc.multipliers))[::-1][:3], np.sort(np.abs(mu))[::-1], atol=1e-6)


def test_a_branch_whose_map_holds_1e_12_only_is_followed_to_the_models_own_gait():
    lc = find_fixed_point(load("compass-gait"), params=LOST)
    assert lc.found_by == "continuation" and lc.residual < 1e-12
    assert lc.stable and lc.step_time == pytest.approx(0.28302, abs=1e-5)  # the default gait, carried there
    _check_against_oracle(LOST, lc)


def test_after_a_fold_collocation_finds_a_gait_of_another_branch_and_says_so():
    lc = find_fixed_point(load("compass-gait"), params=FOLDS)
    assert lc.found_by == "collocation" and lc.residual < 1e-12
    assert "the branch folds at" in lc.search_note and "no gait beyond on this branch" in lc.search_note
    assert "from a walk at these parameters" in lc.search_note and "\n" not in lc.search_note
    _check_against_oracle(FOLDS, lc)
    assert lc.to_json()["found_by"] == "collocation"
    assert not lc.stable  # a saddle far from the default gait (|μ| 47)


@pytest.mark.slow
def test_collocation_after_a_continuation_that_runs_out_of_steps():
    lc = find_fixed_point(load("compass-gait"), params=LONG)
    assert lc.found_by == "collocation" and "400 steps did not reach the end" in lc.search_note
    _check_against_oracle(LONG, lc)


def test_the_routes_that_find_a_gait_are_reported():
    w = load("compass-gait")
    assert find_fixed_point(w).found_by == "walk"
    assert find_fixed_point(w, [-0.2168, 0.3168, 1.0839, 0.3981]).found_by == "guess"


def test_a_system_with_inputs_is_not_solved_by_collocation():
    # its gait depends on the inputs, which an optimiser would choose: that is a design, not the
    # system's own gait
    with pytest.raises(ConvergenceError, match="skipped: the system has inputs"):
        next(collocation_starts(load("rabbit"), {}, 1))


def test_every_route_tried_is_named_in_one_line():
    # the kneed biped's branch folds above the slope asked for, the walk does not converge, and
    # the optimiser does not take a step of two domains (knee unlocked, then locked)
    with pytest.raises(ConvergenceError) as e:
        find_fixed_point(load("kneed-biped"), params={"slope": 0.03})
    msg = str(e.value)
    assert "\n" not in msg
    assert "folds at slope = 0.04515" in msg and "from a walk at these parameters" in msg
    assert "by collocation: not applicable" in msg and "one domain" in msg


def test_the_cli_says_a_gait_was_found_by_collocation_and_why(capsys):
    from amble.cli.main import main

    sets = [a for k, v in FOLDS.items() for a in ("--set", f"{k}={v}")]
    assert main(["limit-cycle", "compass-gait", *sets]) == 0
    out = capsys.readouterr().out
    assert "found by collocation" in out and "the branch folds" in out and "UNSTABLE period-1 gait" in out
