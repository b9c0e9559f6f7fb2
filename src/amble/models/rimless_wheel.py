"""Rimless wheel: a hub mass on equally spaced massless spokes rolling down a slope.

The classic one-degree-of-freedom walker (McGeer 1990; Coleman, Chatterjee & Ruina 1997;
Tedrake, *Underactuated Robotics*, "The Rimless Wheel"). Between impacts the wheel is an
inverted pendulum about the stance spoke's foot; the next spoke's foot strikes the slope when
the stance spoke has passed the slope normal by ``alpha``.

Coordinates (Tedrake's notes and Drake; thesis Eq. 6)::

               next spoke      hub (m)          theta: stance spoke from the vertical,
                      \\       o      /                 foot → hub, positive leaning downhill
                       \\    / |theta/                  (clockwise, the rolling direction)
                        \\  /  |    /   previous
                         \\/   |   /    spoke           spokes: length l, adjacent ones
      ____________________\\___|__/_____________        2 alpha apart
                     stance foot                        slope: descends along +x at gamma

State: ``theta, theta_dot`` (rad, rad/s). The next spoke (ahead, downhill) points from the hub
at ``theta − 2 alpha``; its foot reaches the slope at ``theta = gamma + alpha``. The impact is
*derived*: a perfectly plastic collision of that foot with the ground (``Impact``), which
conserves the angular momentum about the new contact and leaves ``theta_dot+ =
cos(2 alpha) theta_dot−``; the spokes are then relabelled ``theta → theta − 2 alpha``, so every
step starts at ``theta = gamma − alpha``. If the wheel rocks back, the previous spoke strikes
in the same way (relabel ``theta → theta + 2 alpha``); that is not a step.

Closed forms (Tedrake's notes): the rolling fixed point of the post-impact speed is
``omega* = cot(2 alpha) sqrt(4 (g/l) sin(alpha) sin(gamma))``, with multiplier
``cos²(2 alpha)``; it exists when ``omega*`` exceeds ``sqrt(2 (g/l)(1 − cos(gamma − alpha)))``,
the speed needed to carry the hub over the top.

Parameters (Drake's ``examples/rimless_wheel`` defaults; Tedrake's figures use the same):

=========  =========  =======  ===========================================================
name       default    unit     meaning / source
=========  =========  =======  ===========================================================
``m``      1.0        kg       hub mass (Drake default; the gait does not depend on it)
``l``      1.0        m        spoke length (Drake default)
``g``      9.81       m/s²     gravity (Drake default)
``alpha``  π/8        rad      half the angle between adjacent spokes: 8 spokes (Drake)
``slope``  0.08       rad      ramp angle gamma (Drake default; Tedrake's phase portrait)
=========  =========  =======  ===========================================================

Default start: ``theta = slope − alpha`` (just after an impact) and ``theta_dot = 1.5`` rad/s,
faster than the cycle; the fixed-point guess is ``theta_dot = 1.1`` rad/s (the closed form
gives 1.0955 at the defaults).
"""

from __future__ import annotations

import math

from amble import POSITIVE, Guard, Impact, Model, R, Walker, distance_along_slope, height_above_slope, interval, walker

NAME = "rimless-wheel"
POSITION = 60  # place in `amble models` (ascending)

ALPHA = math.pi / 8
SLOPE = 0.08


def build() -> Walker:
    m = Model("rimless-wheel")
    (th,) = m.coordinates("theta")
    mass, l, g, alpha, slope = m.parameters(m=1.0, l=1.0, g=9.81, alpha=ALPHA, slope=SLOPE)
    m.restrict("m l g", POSITIVE)
    m.restrict("alpha", interval(0, math.pi / 2))  # half the angle between spokes: at least two spokes
    m.point("stance_foot", (0, 0))
    hub = m.point("hub", l * R(th), mass=mass, link="stance_foot")
    # Hub → foot of the spoke 2 alpha ahead (downhill) and of the one 2 alpha behind.
    m.point("next_foot", hub - l * R(th - 2 * alpha), link="hub")
    m.point("previous_foot", hub - l * R(th + 2 * alpha), link="hub")
    m.gravity(g)

    start = [SLOPE - ALPHA, 1.5]
    sys_ = walker(m, foot="next_foot", hip="hub", slope=slope, relabel={th: th - 2 * alpha},
                  start=start, guess=[SLOPE - ALPHA, 1.1], doc=__doc__)
    # Rocking back onto the previous spoke: same plastic impact, the other relabelling.
    back = Guard(height_above_slope(m, "previous_foot", slope), -1,
                 distance_along_slope(m, "previous_foot", slope) < 0)
    sys_.transition("back_strike", m.name, back, Impact("previous_foot", {th: th + 2 * alpha}))
    return sys_
