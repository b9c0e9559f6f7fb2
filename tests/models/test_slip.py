"""The SLIP runner against an independent SciPy implementation (tests/oracles/slip.py) and energy."""

import math

from oracles.slip import Slip

import amble
from amble.models.slip import build

M, G, K, L0 = 80.0, 9.81, 20000.0, 1.0


def _energy(x, mode):
    if mode == "stance":
        u, w, ud, wd = x
        return M * G * w + 0.5 * M * (ud**2 + wd**2) + 0.5 * K * (L0 - math.hypot(u, w)) ** 2
    _, y, xd, yd = x
    return M * G * y + 0.5 * M * (xd**2 + yd**2)


def test_energy_conserved_over_100_strides():
    start = [0.0, 0.9402671443810298, 5.115853655768917, 0.0]
    run = amble.simulate(build(snap_to_energy=False), start, steps=100, rtol=1e-12, atol=1e-12, samples=False)
    assert run.status == "completed"
    e0 = _energy(start, "descent")
    worst = max(abs(_energy(ev.x_post, ev.target) - e0) / e0 for ev in run.events)
    assert len(run.events) == 300 and worst <= 1e-10


def test_liftoff_and_apex_map_match_oracle():
    o = Slip()
    s = o.stride(0.95)
    run = amble.simulate(build(), [0.0, 0.95, o.apex_speed(0.95), 0.0], steps=1, samples=False)
    t = {e.name: e.t for e in run.events}
    assert abs(t["liftoff"] - s["t_lo"]) <= 1e-10
    assert abs(run.final_state[1] - s["y_next"]) <= 1e-9


def test_fixed_point_and_multiplier_match_oracle():
    cyc = amble.find_fixed_point(build())
    o = Slip()
    (y,) = [r for r in o.fixed_point(0.93, 0.95, n=3)]
    assert abs(cyc.fixed_point[1] - y) <= 1e-9
    assert abs(cyc.multipliers[0].real - o.multiplier(y)) <= 1e-6 and cyc.stable
