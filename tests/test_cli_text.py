"""The command line's text: gait checks with their margins, numbers rounded, absent values omitted,
and the docs' statements about the models true."""

import re
from pathlib import Path

from amble.analysis.gait_check import GaitCheck
from amble.cli.output import gait_check_lines, number
from amble.cli.sweep import _print as print_sweep

ROOT = Path(__file__).resolve().parents[1]


def test_gait_checks_name_only_failed_checks_and_give_margins_in_units():
    check = GaitCheck(min_normal_force=274.04, max_friction_ratio=0.3263, min_swing_clearance=-0.00035,
                      min_normal_impulse=16.73, min_trailing_foot_lift_speed=0.3746, max_input_ratio=0.74, mu=0.7,
                      normal_force_positive=True, friction_ok=True, swing_foot_clear=False, impulse_positive=True,
                      trailing_foot_leaves=True, within_limits=True)
    lines = gait_check_lines(check.to_json())
    assert lines[0] == "gait checks: FAILED swing_foot_clear"  # the summary key "ok" is no check
    text = "\n".join(lines)
    assert "FAILED swing-foot clearance, min: -0.35 mm (> 0)" in " ".join(text.split())
    assert "274 N" in text and "16.73 N·s" in text and "0.3746 m/s" in text and "μ = 0.7" in text
    assert len(lines) == 7
    # a dimensionless model: the same lines without units, the clearance not rescaled
    plain = gait_check_lines(check.to_json(), si=False)
    assert "-0.00035 (> 0)" in plain[3] and " N" not in plain[1]


def test_numbers_are_rounded_and_missing_ones_are_a_dash():
    assert number(0.07769230769230769) == "0.07769"
    assert number(None) == "—" and number(float("nan")) == "—"


def test_sweep_text_omits_absent_results_and_rounds(capsys):
    summary = {"kind": "fixed-point", "model": "compass-gait", "parameters": ["slope"], "points": 50, "ok": 50,
               "failed": 0, "seconds": 1.0, "period_doubling": None, "stable_range": [0.01, 0.07769230769230769]}
    print_sweep(summary, None, None)
    out = capsys.readouterr().out
    assert "None" not in out and "period doubling" not in out
    assert "stable range: slope = 0.01 → 0.0776923" in out
    assert "0.07769230769230769" not in out


def test_docs_say_what_amble_does():
    readme = (ROOT / "README.md").read_text()
    assert "no trajectory optimisation" not in readme
    from amble.models import load

    tutorial = (ROOT / "docs" / "tutorial.md").read_text()
    rows = dict(re.findall(r"^\| (3D humanoid|2D humanoid|kneed biped|compass gait) \| (\d+) \|", tutorial, re.M))
    names = {"compass gait": "compass-gait", "kneed biped": "kneed-biped", "2D humanoid": "humanoid-2d",
             "3D humanoid": "humanoid-3d"}
    assert len(rows) == 4
    for label, modes in rows.items():
        assert int(modes) == len(load(names[label]).mode_names), label
