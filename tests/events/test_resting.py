"""With restitution 0, or a ball released on the floor, the run
fell through the floor silently (z = −447 m, status end_time). A bounce written as a plain
transition with an Explicit reset has no resting mode: the run ends at the floor as ``zeno`` (the
impacts accumulate), at the closed-form landing time, instead of lying. Declared with
``unilateral_contact`` it comes to rest and the run goes on (test_resting_contact.py)."""

import math

import pytest

import amble
from amble import Explicit, Guard, HybridSystem, Model


def _ball(name: str) -> HybridSystem:
    m = Model(name)
    x, z = m.coordinates("x z")
    mass, g, e = m.parameters(mass=1.0, g=9.81, e=0.0)
    m.point("p", (x, z), mass=mass)
    m.gravity(g)
    xd, zd = m.qd
    s = HybridSystem(name, m)
    s.transition("bounce", name, Guard(z, -1), Explicit(q=[x, z], qd=[xd, -e * zd]))
    return s


def test_restitution_zero_stops_at_the_floor():
    tr = amble.simulate(_ball("ev-ball-e0"), [0.0, 1.0, 0.0, 0.0], t_end=10.0)
    assert tr.status == "zeno", tr.message  # before: end_time with z = −447 m
    assert tr.t[-1] == pytest.approx(math.sqrt(2 / 9.81), abs=1e-9)
    assert abs(tr.final_state[1]) < 1e-12 and abs(tr.final_state[3]) < 1e-12


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_a_ball_released_on_the_floor_does_not_sink(e):
    tr = amble.simulate(_ball("ev-ball-floor"), [0.0, 0.0, 0.0, 0.0], params={"e": e}, t_end=10.0)
    assert tr.status == "zeno", tr.message  # before: end_time with z = −490 m
    assert tr.t[-1] < 1e-6
    assert abs(tr.final_state[1]) < 1e-12
