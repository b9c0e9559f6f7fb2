"""Searches end and gaits are gaits. A fixed-point search on a
system without a step transition ran forever; a period of 10⁶ ran past 180 s; a wheel at rest was
a "stable period-1 gait" with step time 2e-8 s; a period-2 search returned the period-1 gait
twice over as "period-2"."""

import math
import time

import numpy as np
import pytest
from systems import guarded_pendulum

from amble.analysis.poincare import find_fixed_point
from amble.errors import ConvergenceError, ModelError, StateError
from amble.models import compass_gait, rimless_wheel

# Goswami et al. (1997) / thesis Table 2 compass gait at slope 0.05: post-impact fixed point
_COMPASS_PUBLISHED = np.array([-0.2168, 0.3168, 1.0839, 0.3981])


def test_a_system_without_step_transition_has_no_return_map():
    t0 = time.monotonic()
    with pytest.raises(ModelError, match="no step transition"):
        find_fixed_point(guarded_pendulum("ev-nostep"), [0.1, 0.0])
    assert time.monotonic() - t0 < 30


def test_the_period_is_bounded():
    t0 = time.monotonic()
    with pytest.raises(StateError, match="at most"):
        find_fixed_point(compass_gait.build(), period=1_000_000)
    assert time.monotonic() - t0 < 30


def test_a_wheel_at_rest_is_not_a_gait():
    with pytest.raises(ConvergenceError, match="at rest"):
        find_fixed_point(rimless_wheel.build(), params={"slope": -0.08})


def test_the_rolling_wheel_is_still_a_gait():
    lc = find_fixed_point(rimless_wheel.build())
    # closed form: ω⁺ = cos 2α ω⁻ and ω⁻² = ω⁺² + 4 (g/l) sin α sin γ  ⇒
    # ω⁺² = cos²2α · 4 (g/l) sin α sin γ / (1 − cos²2α)
    a, gam = math.pi / 8, 0.08
    c2 = math.cos(2 * a) ** 2
    w = math.sqrt(c2 * 4 * 9.81 * math.sin(a) * math.sin(gam) / (1 - c2))
    assert lc.fixed_point[1] == pytest.approx(w, abs=1e-8)
    assert lc.step_time > 0.5


def test_a_period_two_search_reports_the_period_one_gait():
    lc = find_fixed_point(compass_gait.build(), period=2)
    assert lc.period == 1
    assert np.allclose(lc.fixed_point, _COMPASS_PUBLISHED, atol=2e-4)
