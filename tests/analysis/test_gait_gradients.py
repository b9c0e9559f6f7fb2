"""Gait gradients by the implicit function theorem against re-converged fixed points."""

import numpy as np
import pytest

from amble.analysis.gait_gradients import gait_gradients, gait_speed
from amble.analysis.poincare import find_fixed_point
from amble.errors import StateError
from amble.models import load


@pytest.fixture(scope="module")
def compass():
    return load("compass-gait")


def _central(system, cycle, name, h):
    """Richardson-extrapolated central differences of independently re-converged gaits."""
    def at(dp):
        lc = find_fixed_point(system, cycle.fixed_point, params={**cycle.parameters, name: cycle.parameters[name] + dp})
        return np.r_[lc.fixed_point, lc.step_time, gait_speed(lc), np.max(np.abs(lc.multipliers))]
    d1 = (at(h) - at(-h)) / (2 * h)
    d2 = (at(h / 2) - at(-h / 2)) / h
    return (4 * d2 - d1) / 3


def test_fixed_point_step_time_speed_and_radius(compass):
    lc = find_fixed_point(compass)
    g = gait_gradients(lc, ["slope", "mh"])
    for j, (name, h) in enumerate([("slope", 1e-3), ("mh", 1e-2)]):
        ref = _central(compass, lc, name, h)
        n = lc.fixed_point.size
        np.testing.assert_allclose(g.fixed_point[:, j], ref[:n], atol=1e-6 * max(1, np.max(np.abs(ref[:n]))))
        assert g.step_time[j] == pytest.approx(ref[n], abs=1e-6 * max(1, abs(ref[n])))
        assert g.speed[j] == pytest.approx(ref[n + 1], abs=1e-5 * max(1, abs(ref[n + 1])))
        assert g.spectral_radius[j] == pytest.approx(ref[n + 2], abs=1e-5 * max(1, abs(ref[n + 2])))
    # a steeper slope walks faster, with longer steps: the signs are physical
    assert g.speed[0] > 0


def test_unknown_parameter_is_refused(compass):
    lc = find_fixed_point(compass)
    with pytest.raises(StateError, match="unknown parameter"):
        gait_gradients(lc, ["nope"])
