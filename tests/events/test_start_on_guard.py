"""A run started exactly on a step transition's guard does not fire it at t = 0: the start is
the run's first section point and the first step is the next crossing. An impact guard the run
starts on, the flow pressing into it, still fires at once (a ball started on the floor moving
down bounces; it does not sink through).

The model: a ball bouncing elastically on a floor (impact ``y`` falling through 0, ``ẏ → −ẏ``)
with a step at each apex (``ẏ`` falling through 0). From rest at height h the floor is reached
after T = sqrt(2 h / g) and each apex follows 2 T after the one before."""

import math

import sympy as sp

import amble
from amble import Explicit, Guard, HybridSystem, Model

G = 9.81


def _ball() -> HybridSystem:
    m = Model("ball-apex-steps")
    (y,) = m.coordinates(["y"])
    (yd,) = m.qd
    m.point("ball", sp.Matrix([0, y]), mass=1.0)
    m.gravity(G)
    s = HybridSystem("ball-apex-steps", {"air": m})
    s.transition("floor", "air", Guard(y, -1), Explicit(q=[y], qd=[-yd]), target="air")
    s.transition("apex", "air", Guard(yd, -1), Explicit(q=[y], qd=[yd]), target="air", step=True)
    return s


def test_a_run_started_on_a_step_guard_does_not_step_at_once():
    run = amble.simulate(_ball(), [1.0, 0.0], steps=2, rtol=1e-12, atol=1e-12)
    assert run.status == "completed", run.message
    T = math.sqrt(2 * 1.0 / G)
    apexes = [e.t for e in run.events if e.name == "apex"]
    floors = [e.t for e in run.events if e.name == "floor"]
    assert len(apexes) == 2  # before: an apex at t = 2e-16, then one at 2 T
    assert abs(apexes[0] - 2 * T) <= 1e-9 and abs(apexes[1] - 4 * T) <= 1e-9
    assert abs(floors[0] - T) <= 1e-9


def test_negative_zero_is_on_the_guard_too():
    run = amble.simulate(_ball(), [1.0, -0.0], steps=1, rtol=1e-12, atol=1e-12)
    assert abs(run.events[-1].t - 2 * math.sqrt(2 / G)) <= 1e-9


def test_a_run_started_on_an_impact_guard_moving_into_it_strikes_at_once():
    run = amble.simulate(_ball(), [0.0, -1.0], steps=1, rtol=1e-12, atol=1e-12)
    first, apex = run.events[0], run.events[-1]
    assert first.name == "floor" and first.t <= 1e-12 and abs(first.x_post[1] - 1.0) <= 1e-12
    assert apex.name == "apex" and abs(apex.t - 1 / G) <= 1e-9 and abs(apex.x_post[0] - 1 / (2 * G)) <= 1e-9
