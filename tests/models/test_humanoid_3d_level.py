"""The 3D humanoid on level ground under controlled symmetry walks the slope gait of humanoid-3d-yaw
turned about the lateral axis: fixed point, step time and the return map conjugate by the turn."""

import numpy as np
import pytest

from amble.analysis.poincare import ReturnMap, find_fixed_point
from amble.models import load

SHIFT = np.array([0.05, 0.05, 0, 0, 0.05, 0, 0] + [0] * 7)  # stance, swing, torso turn by γ


def test_level_gait_is_the_slope_gait_turned():
    level = find_fixed_point(load("humanoid-3d-level"))
    slope = find_fixed_point(load("humanoid-3d-yaw"))
    np.testing.assert_allclose(level.fixed_point, slope.fixed_point - SHIFT, rtol=0, atol=1e-9)
    assert level.step_time == pytest.approx(slope.step_time, abs=1e-9)
    np.testing.assert_allclose(np.sort_complex(level.multipliers), np.sort_complex(slope.multipliers), atol=1e-6)
    assert level.stable
    Pl, Ps = ReturnMap(load("humanoid-3d-level"), None), ReturnMap(load("humanoid-3d-yaw"), None)
    dx = 1e-3 * np.random.default_rng(3).standard_normal(14)
    xs, ts = Ps(slope.fixed_point + dx)
    xl, tl = Pl(slope.fixed_point + dx - SHIFT)
    np.testing.assert_allclose(xl, xs - SHIFT, rtol=0, atol=1e-9)
    assert tl == pytest.approx(ts, abs=1e-9)
