"""Vertical one-legged hopper: a body bouncing on a damped spring leg that thrusts at the bottom.

The vertical core of Raibert's hopping machines (Raibert 1986, *Legged Robots That Balance*,
ch. 2: a spring leg, a thrust in stance, a leg held at its length in flight). A body of mass
``m`` on a massless leg: a linear spring ``k`` and a damper ``c`` in parallel. The damper takes
energy out in every stance; the thrust puts it back, and the hops settle on a limit cycle::

        o  body (y)            flight: the leg held at its rest length L below the body
        |
        /  spring k, damper c  stance: the foot on the ground, the body on the leg
        \\
    ____|____ foot

* **flight**: ``y`` (m), the body's height above the ground; ballistic.
* **touchdown** (flight → compression): ``y`` falls through ``L``; the leg is massless, so the
  state is unchanged.
* **compression**: ``m ÿ = k (L − y) − c ẏ − m g``.
* **bottom** (compression → thrust): ``ẏ`` rises through zero; the actuator lengthens the
  spring's rest length by ``delta`` at once (the spring's energy rises by
  ``k delta (L − y) + k delta²/2``).
* **thrust**: ``m ÿ = k (L + delta − y) − c ẏ − m g``.
* **liftoff** (thrust → flight): the ground's force on the foot, ``λ = k (L + delta − y) − c ẏ``
  (N), falls through zero. With a damper this is before the spring reaches its rest length.
* **apex** (flight → flight, the step of the return map): ``ẏ`` falls through zero. One flight
  domain serves: a run started at an apex (on the step's guard) takes it as its first section
  point and steps at the next apex.
* the body reaching the ground ends the run (``fell``).

State ``y, y_dot`` (m, m/s) in every domain. The Poincaré section is the apex ``(y, 0)``: apex
height → next apex height, a one-dimensional map with one multiplier.

Parameters (a hopper of robot size; not from a publication):

=========  =======  =====  =================================================
name       default  unit   meaning
=========  =======  =====  =================================================
``m``      10       kg     body mass
``L``      0.5      m      leg rest length
``k``      4000     N/m    leg stiffness
``c``      80       N s/m  leg damping (damping ratio 0.2)
``delta``  0.05     m      thrust: lengthening of the rest length at the bottom
``g``      9.81     m/s²   gravity
=========  =======  =====  =================================================

At the defaults the hopper settles on apexes 0.64310 m high, the foot leaving the ground with
the body at 0.5188 m; multiplier 0.471 (stable).
"""

from __future__ import annotations

import sympy as sp

from amble import POSITIVE, Explicit, Guard, HybridSystem, Model

NAME = "vertical-hopper"
POSITION = 75  # place in `amble models` (ascending)

PARAMS = dict(m=10.0, L=0.5, k=4000.0, c=80.0, delta=0.05, g=9.81)


def _domain(name: str, rest: sp.Expr | None) -> Model:
    """A domain in ``y``; ``rest``: the spring's rest length in stance (None: flight)."""
    d = Model(name)
    (y,) = d.coordinates("y", unit="m")
    (yd,) = d.qd
    m, L, k, c, delta, g = d.parameters(**PARAMS)
    d.restrict("m L k g", POSITIVE)
    d.point("body", (0, y), mass=m)
    d.gravity(g)
    if rest is not None:
        length = L + delta if rest == "thrust" else L
        d.add_potential(k * (length - y) ** 2 / 2)
        d.force([-c * yd])
    return d


def build() -> HybridSystem:
    """The hopper: flight, compression, thrust (state ``y, y_dot`` in each)."""
    fl, co, th = _domain("flight", None), _domain("compression", "compression"), _domain("thrust", "thrust")
    y, yd = fl.q[0], fl.qd[0]
    L, k, c, delta = (fl.symbol(n) for n in ("L", "k", "c", "delta"))
    s = HybridSystem(NAME, {"flight": fl, "compression": co, "thrust": th}, max_step_time=10.0, doc=__doc__)
    same = Explicit(q=[y], qd=[yd])
    s.transition("touchdown", "flight", Guard(y - L, -1), same, "compression")
    yc, ycd = co.q[0], co.qd[0]
    s.transition("bottom", "compression", Guard(ycd, 1), Explicit(q=[yc], qd=[ycd]), "thrust")
    yt, ytd = th.q[0], th.qd[0]
    ground_force = k * (L + delta - yt) - c * ytd  # N: the spring and damper push the foot down
    s.transition("liftoff", "thrust", Guard(ground_force, -1), Explicit(q=[yt], qd=[ytd]), "flight")
    # ẏ = 0 exactly at the apex (the located root is within round-off of it): the section point
    s.transition("apex", "flight", Guard(yd, -1), Explicit(q=[y], qd=[0]), "flight", step=True)
    for name, mode in (("fell", "compression"), ("fell_in_thrust", "thrust")):
        s.terminal(name, mode, Guard(s.modes[mode].q[0], -1), status="fell")
    s.default_start["flight"] = [0.8, 0.0]
    s.fixed_point_guess = [0.64, 0.0]
    return s
