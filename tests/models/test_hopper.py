"""The vertical hopper against an independent SciPy hopper (tests/oracles/hopper.py)."""

from oracles.hopper import Hopper

import amble
from amble.models.hopper import build


def test_one_hop_from_an_apex_matches_oracle():
    o = Hopper()
    ref = o.stride(0.8)
    run = amble.simulate(build(), [0.8, 0.0], mode="flight", steps=1, rtol=1e-12, atol=1e-12, samples=False)
    assert run.status == "completed", run.message
    t = {e.name: e.t for e in run.events}
    assert list(t) == ["touchdown", "bottom", "liftoff", "apex"]  # no apex at t = 0 from the start
    for name, key in (("touchdown", "t_td"), ("bottom", "t_bottom"), ("liftoff", "t_lo"), ("apex", "t_apex")):
        assert abs(t[name] - ref[key]) <= 1e-10, name
    assert abs(run.final_state[0] - ref["y_next"]) <= 1e-10


def test_limit_cycle_and_multiplier_match_oracle():
    o = Hopper()
    (y,) = o.fixed_point(0.6, 0.7, n=3)
    cyc = amble.find_fixed_point(build())
    assert abs(cyc.fixed_point[0] - y) <= 1e-9 and abs(cyc.fixed_point[1]) <= 1e-9
    assert abs(cyc.multipliers[0].real - o.multiplier(y)) <= 1e-6 and cyc.stable
    assert abs(cyc.step_time - o.stride(y)["t_apex"]) <= 1e-9
