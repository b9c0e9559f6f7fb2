"""The README's table of library models says what the models do: each row's coordinates, step
time, leading multipliers and stability are those of the model's fixed point found now."""

import re
from pathlib import Path

import numpy as np
import pytest

from amble import find_fixed_point
from amble.models import load, names

README = Path(__file__).resolve().parents[1] / "README.md"


def _rows() -> list[list[str]]:
    text = README.read_text()
    head = text.index("| model | source | coordinates | step time |")
    rows = []
    for line in text[head:].splitlines()[2:]:
        if not line.startswith("| `"):
            break
        rows.append([c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]])
    return rows


ROWS = _rows()


def test_the_table_lists_every_library_model_once():
    listed = [r[0].strip("`") for r in ROWS]
    assert sorted(listed) == sorted(names())


@pytest.mark.parametrize("row", ROWS, ids=[r[0].strip("`") for r in ROWS])
def test_a_row_is_what_the_model_does(row):
    name, _, coords, step, mults, stable = row
    s = load(name.strip("`"))
    counts = [int(c) for c in re.findall(r"\d+", coords)]
    modes = [len(s.state_names(m)) // 2 for m in s.mode_names]
    assert counts[0] == modes[0] and set(counts) <= set(modes)
    lc = find_fixed_point(s)
    assert lc.residual < 1e-9
    shown = float(re.match(r"[\d.]+", step).group())
    digits = len(step.split(".")[1].split()[0])
    assert abs(lc.step_time - shown) <= 0.51 * 10.0**-digits, (lc.step_time, step)
    given = [float(v) for v in re.findall(r"\d+\.\d+", mults)]
    found = np.sort(np.abs(lc.multipliers))[::-1]
    order = np.argsort(-np.array(given))  # the row may list a multiplier > 1 first or in its own order
    assert np.allclose(np.array(given)[order], found[:len(given)], atol=0.0051), (given, found)
    assert stable.startswith("yes") == bool(lc.stable)
