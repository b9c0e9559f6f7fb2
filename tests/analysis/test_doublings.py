"""The compass gait's period-doubling cascade (amble.period_doublings) against Feigenbaum's
universal constant and the defining property of a flip.

The compass gait period-doubles first at slope ≈ 0.07664 rad, then again and again in ever shorter
intervals. docs/references.md (section 1) gives Goswami, Thuilot & Espiau's values as transcribed
[T] — first doubling 4.37°, second 4.9°, the 8-periodic gait at 5.01° — and re-computed ones [R]
by Goswami's equations integrated with SciPy (tests/oracles/compass_gait.py): 4.391° and 4.914°.
For a family of maps with a quadratic extremum the ratio of successive intervals tends to
Feigenbaum's δ = 4.6692016… (M. J. Feigenbaum, J. Stat. Phys. 19:25–52, 1978) — a constant no
walker model enters.
"""

from __future__ import annotations

import numpy as np
import pytest

import amble
from amble.analysis.doublings import FEIGENBAUM_DELTA, period_doublings
from amble.errors import StateError


def _check(cascade, levels):
    assert [b.period for b in cascade.branches] == [2**n for n in range(levels)]
    assert len(cascade.flips) == levels and all(f.located for f in cascade.flips)
    assert np.all(np.diff(cascade.values) > 0)
    for f in cascade.flips:  # a flip: a real multiplier −1 of the period-2^n gait there
        assert np.min(np.abs(f.point.multipliers + 1)) < 1e-6
    for b in cascade.branches[1:]:  # a period-doubled orbit, not the shorter one repeated
        a, c = b.points[-1].orbit[0], b.points[-1].orbit[b.period // 2]
        assert np.max(np.abs(a - c)) > 1e-6


def test_compass_gait_cascade_to_period_eight(compass):
    cascade = period_doublings(compass, "slope", 0.075, 0.088, levels=4)
    _check(cascade, 4)
    first, second, third, _ = np.degrees(cascade.values)
    assert first == pytest.approx(4.391, abs=1e-3) and first == pytest.approx(4.37, abs=0.03)  # [R], [T]
    assert second == pytest.approx(4.914, abs=1e-3) and second == pytest.approx(4.9, abs=0.05)  # [R], [T]
    assert third == pytest.approx(5.01, abs=0.01)  # [T]: the period-4 gait doubles into the 8-periodic one
    d1, d2 = cascade.ratios
    # the ratios approach Feigenbaum's δ: the second already within 1 %
    assert abs(d2 - FEIGENBAUM_DELTA) < abs(d1 - FEIGENBAUM_DELTA)
    assert d2 == pytest.approx(FEIGENBAUM_DELTA, rel=1e-2)
    out = cascade.to_json()
    assert out["periods"] == [1, 2, 4, 8] and len(out["ratios"]) == 2


@pytest.mark.slow
def test_compass_gait_cascade_to_period_sixteen(compass):
    cascade = period_doublings(compass, "slope", 0.075, 0.09, levels=5)
    _check(cascade, 5)
    assert cascade.ratios[-1] == pytest.approx(FEIGENBAUM_DELTA, rel=3e-3)


def test_levels_are_checked(compass):
    with pytest.raises(StateError):
        period_doublings(compass, "slope", 0.075, 0.088, levels=0)
    assert amble.period_doublings is period_doublings
