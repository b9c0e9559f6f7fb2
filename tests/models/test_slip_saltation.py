"""The exact sensitivities of the SLIP stride (variational equations and saltation matrices at
touchdown, liftoff and apex) against central differences of the independent SciPy runner's
stride (tests/oracles/slip.py) from the same flight state, event by event.

A run capped at its first, second and third event ends just after touchdown, liftoff and the
apex; its ``dx_dx0``/``dt_dx0`` then hold the product of flows and saltation matrices up to that
event. The apex reset here keeps the energy the stride has (``snap_to_energy=False``), so the map
is the flow's own; the start is a descending flight state off the apex (``ẏ ≠ 0``), so every
direction of the state is exercised."""

import numpy as np
import pytest
from oracles.slip import Slip

from amble.analysis.poincare import ReturnMap
from amble.models.slip import build
from amble.simulation.engine import Options, run

X0 = np.array([0.1, 0.97, 5.05, -0.4])  # x (m), y (m), x_dot, y_dot (m/s): falling, before touchdown
EVENTS = ("touchdown", "liftoff", "apex")


def _oracle_jacobians(h: float = 1e-6) -> dict:
    """∂(event state)/∂x0 and ∂(event time)/∂x0 by central differences of the oracle's stride."""
    o = Slip()
    out = {e: (np.zeros((4, 4)), np.zeros(4)) for e in EVENTS}
    for j in range(4):
        d = np.zeros(4)
        d[j] = h
        plus, minus = o.from_flight(*(X0 + d)), o.from_flight(*(X0 - d))
        for e in EVENTS:
            out[e][0][:, j] = (plus[e][1] - minus[e][1]) / (2 * h)
            out[e][1][j] = (plus[e][0] - minus[e][0]) / (2 * h)
    return out


@pytest.fixture(scope="module")
def amble_map():
    return ReturnMap(build(snap_to_energy=False))


@pytest.mark.parametrize("n", [1, 2, 3], ids=EVENTS)
def test_event_sensitivities_match_oracle_differences(amble_map, n):
    P = amble_map
    r = run(P.k, P.p, P.mi, X0, steps=1, opts=Options(rtol=1e-12, atol=1e-12, max_events=n),
            sensitivities="state")
    ref_x, ref_t = _oracle_jacobians()[EVENTS[n - 1]]
    s = r.sensitivity
    assert r.events == n
    # the state itself, then its derivatives (oracle differences: ~1e-6 from the 1e-13 integration)
    ox = Slip().from_flight(*X0)[EVENTS[n - 1]]
    assert abs(r.t - ox[0]) <= 1e-10 and np.max(np.abs(r.x - ox[1])) <= 1e-9
    assert np.max(np.abs(s.dx_dx0 - ref_x)) <= 2e-6 * max(1.0, np.max(np.abs(ref_x)))
    assert np.max(np.abs(s.dt_dx0 - ref_t)) <= 2e-6 * max(1.0, np.max(np.abs(ref_t)))


def test_stride_jacobian_exact_equals_amble_differences(amble_map):
    # consistency: the exact Jacobian of the whole stride against differences of amble's own map
    P = amble_map
    x, _, s = P.derivatives(X0, params=False)
    h, fd = 1e-6, np.zeros((4, 4))
    for j in range(4):
        d = np.zeros(4)
        d[j] = h
        fd[:, j] = (P(X0 + d)[0] - P(X0 - d)[0]) / (2 * h)
    assert np.max(np.abs(s.dx_dx0 - fd)) <= 1e-5 * max(1.0, np.max(np.abs(fd)))
