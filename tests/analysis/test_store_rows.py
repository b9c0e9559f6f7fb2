"""Rows read back from a result file are trusted only if every cell is of its column's type."""

from __future__ import annotations

import pytest

from amble.analysis.store import ResultFileWarning, ResultStore

TYPES = {"i": "int", "status": "str", "step_time": "float", "stable": "bool", "moduli": "json"}


def test_rows_not_of_their_columns_types_are_ignored(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("i,status,step_time,stable,moduli\n"
                    "0,ok,0.73,true,[0.5]\n"      # good
                    "1,ok,abc,true,[0.5]\n"       # step_time not a number: once counted ok
                    "2,ok,0.73,yes,[0.5]\n"       # not a bool as written
                    "3,ok,0.73,true,[0.5\n"       # not JSON
                    "x,ok,0.73,true,[0.5]\n"      # a key that is not an index
                    "5,failed,,,\n", encoding="utf-8")  # empty cells: a failed point, fine
    with pytest.warns(ResultFileWarning, match=r"4 damaged row\(s\).*line 3: step_time = 'abc' is not float"):
        store = ResultStore(path, TYPES, ["i"])
    with store:
        assert sorted(store.rows) == [("0",), ("5",)]
        assert store.ignored == 4


def test_untyped_columns_keep_every_complete_row(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("i,v\n0,abc\n", encoding="utf-8")
    with ResultStore(path, ["i", "v"], ["i"]) as store:
        assert store.rows == {("0",): {"i": "0", "v": "abc"}}
