"""``python -m benchmarks --only X`` replaces only section X (and its goal rows) in BENCHMARKS.md.

Truth: the text of the other sections, the other goal rows and hand-written prose are kept byte
for byte; the chosen section and its goal rows are the new ones; running twice leaves one note.
"""

from __future__ import annotations

import pytest

main_mod = pytest.importorskip("benchmarks.__main__")
common = pytest.importorskip("benchmarks.common")

OLD = """# amble benchmarks

Run 2026-01-01 00:00 UTC, 10.0 min in all.

## Machine

| | |
|:---|---:|
| CPU | x |

## Goals

| goal | target | measured (median) |  |
|:---|---:|---:|---:|
| a first | ≤ 1 | 0.5 | met |
| sweep one | ≥ 2 | 1.0 | **missed** |
| a last | ≤ 3 | 2.0 | met |

## Walking

walk body

## Sweeps

old sweep body

## Closing note: by hand

prose kept
"""


def test_only_the_chosen_section_and_its_goal_rows_are_replaced():
    Goal, Section = common.Goal, common.Section
    goals = [Goal("sweep one", "≥ 2", "2.5", True), Goal("sweep two", "t", "m", None)]
    sec = Section("Sweeps", "new sweep body", goals)
    new = main_mod.splice(OLD, [sec], "python -m benchmarks --only sweep", {}, 60.0)
    assert "new sweep body" in new and "old sweep body" not in new
    assert "walk body" in new and "prose kept" in new and "| CPU | x |" in new
    rows = [ln for ln in new.splitlines() if ln.startswith("| ") and "|:" not in ln][3:]
    assert rows == ["| a first | ≤ 1 | 0.5 | met |", "| sweep one | ≥ 2 | 2.5 | met |",
                    "| sweep two | t | m | not measured |", "| a last | ≤ 3 | 2.0 | met |"]
    assert new.count("Re-run ") == 1 and "*Sweeps* only" in new
    again = main_mod.splice(new, [sec], "python -m benchmarks --only sweep", {}, 60.0)
    assert again.count("Re-run ") == 1 and again.splitlines()[3:] == new.splitlines()[3:]
    assert new.index("## Walking") < new.index("## Sweeps") < new.index("## Closing note")
