"""Simplest walker: the m/M → 0 limit of a compass gait with point feet (Garcia et al. 1998).

Two rigid massless legs of length ``l`` hinged at a hip of mass ``M``, point feet of mass
``m``, walking down a slope ``γ`` powered by gravity alone. In the limit ``β = m/M → 0`` the
hip moves as an inverted pendulum that the feet do not disturb, and the swing leg is a
pendulum hanging from the moving hip. Everything is scaled: lengths by ``l``, masses by
``M``, time by ``sqrt(l/g)`` (so one time unit is ``sqrt(l/g)`` seconds, velocities are in
rad per ``sqrt(l/g)``). The slope is the only parameter.

Coordinates (as in Garcia et al. 1998), both angles measured *from the slope normal*::

                  hip (M)
                  /\\            theta: stance leg from the slope normal, positive when the
                 /  \\                  hip is uphill of the stance foot (the walker moves with
      stance   /    \\  swing           theta decreasing, from +theta* after heel strike to
      leg     / theta \\ leg             about −theta* at the next one)
             /  | phi  \\        phi:   angle from the stance leg to the swing leg, same sense;
    ________/___|_______\\____          the swing leg makes ``theta − phi`` with the normal
    stance foot  normal   swing foot    (phi = 0: legs together)
      (m → 0)               (m → 0)
    slope descends to the right (+x, the walking direction) at gamma

In amble's world frame (angles from the true vertical, positive leaning downhill) the stance
leg is at ``gamma − theta`` and the swing leg at ``gamma − theta + phi``.

Equations of motion (Garcia et al. 1998; the limit β → 0 of the compass gait)::

    theta'' = sin(theta − gamma)
    phi''   = theta'' + theta'² sin(phi) − cos(theta − gamma) sin(phi)

The first is Lagrangian (the hip pendulum: ``K = theta'²/2``, ``V = cos(theta − gamma)``,
the hip's height above the stance foot in units of ``l``). The second is not: at β = 0 the swing leg is driven by
the hip but exerts no force back, a one-way coupling no Lagrangian has. It is therefore
given a unit inertia (``K += phi'²/2``) and its right-hand side as a generalized force. The
energy columns are thus the hip's energy plus ``phi'²/2``; the hip's ``theta'²/2 +
cos(theta − gamma)`` alone is conserved during a step.

Heel strike (Garcia et al. 1998): the swing foot is on the slope when
``phi − 2 theta = 0``. That surface is also crossed near mid-stance when the legs pass each
other (the swing foot scuffs through the ground, which the model ignores): there
``phi − 2 theta`` goes from positive to negative, while at heel strike it rises back to zero
with the stance leg past the normal. The guard is therefore ``phi − 2 theta`` with
direction +1 and enabled only for ``theta < 0``. The reset is the published limit of the
plastic impact and leg swap (angular momentum about the new contact, then about the hip)::

    theta+ = −theta−                         phi+ = −2 theta−
    theta'+ = cos(2 theta−) theta'−          phi'+ = cos(2 theta−) (1 − cos(2 theta−)) theta'−

(the finite-β map divides ``theta'+`` by ``1 + β sin²(2 theta−)``; its β → 0 limit is above).

Parameters:

=========  =======  ====  ===================================================================
name       default  unit  source
=========  =======  ====  ===================================================================
``slope``  0.009    rad   Garcia et al. 1998 (the slope of their period-one results)
=========  =======  ====  ===================================================================

Default start and fixed-point guess: the stable ("long-period") gait at γ = 0.009,
``theta = 0.2003109, phi = 2 theta, theta' = −0.1998325, phi' = (1 − cos 2 theta) theta'``
(Garcia et al. 1998; the simulation code distributed with the paper prints
0.20031090049483 / −0.19983247291764 and the multipliers −0.1912 ± 0.5563i).

Reference: M. Garcia, A. Chatterjee, A. Ruina, M. Coleman, "The simplest walking model:
stability, complexity, and scaling", ASME J. Biomech. Eng. 120(2):281–288, 1998.
"""

from __future__ import annotations

import math

import sympy as sp

from amble import Explicit, Guard, Model, R, Walker, height_above_slope

NAME = "simplest-walker"
POSITION = 50  # place in `amble models` (ascending)

#: Post-heel-strike state of the stable gait at γ = 0.009 (Garcia et al. 1998), rounded to 7 digits.
THETA_STAR = 0.2003109
THETA_DOT_STAR = -0.1998325


def _on_cycle(theta: float, theta_dot: float) -> list[float]:
    """A post-heel-strike state (theta, phi, theta', phi') with the feet on the section."""
    return [theta, 2.0 * theta, theta_dot, (1.0 - math.cos(2.0 * theta)) * theta_dot]


def build() -> Walker:
    m = Model("simplest-walker", time_unit="√(l/g)")
    th, ph = m.coordinates("theta phi")
    thd, phd = m.dot(th), m.dot(ph)
    slope = m.parameter("slope", 0.009, "ramp angle γ (rad), descending along +x")

    # Points in amble's frame: leg angles from the true vertical, positive downhill. The hip
    # carries the unit mass M (scaled), which is what K and V below say; the feet's β → 0.
    m.point("stance_foot", (0, 0))
    hip = m.point("hip", R(slope - th), mass=1, link="stance_foot")
    m.point("swing_foot", hip - R(slope - th + ph), link="hip")

    # The hip is a Lagrangian inverted pendulum; the swing leg has unit inertia and is driven
    # by a generalized force equal to the right-hand side of Garcia's swing-leg equation.
    m.K = thd**2 / 2 + phd**2 / 2
    m.V = sp.cos(th - slope)
    th_dd = sp.sin(th - slope)
    m.force([0, th_dd + thd**2 * sp.sin(ph) - sp.cos(th - slope) * sp.sin(ph)])

    c = sp.cos(2 * th)
    reset = Explicit(q={th: -th, ph: -2 * th}, qd={thd: c * thd, phd: c * (1 - c) * thd}, shift="swing_foot")

    sys_ = Walker(m.name, {m.name: m}, max_step_time=20.0, hip="hip", slope=slope,  # a step: ≈ 3.8 time units
                  doc=__doc__)
    # phi − 2 theta rises through zero at heel strike (theta < 0); its downward crossing near
    # mid-stance is the ignored foot scuffing.
    sys_.transition("heel_strike", m.name, Guard(ph - 2 * th, +1, th < 0), reset, step=True)
    sys_.terminal("hip_on_ground", m.name, Guard(height_above_slope(m, "hip", slope), -1), status="fell")
    start = _on_cycle(THETA_STAR, THETA_DOT_STAR)
    sys_.default_start[m.name] = start
    sys_.fixed_point_guess = list(start)
    return sys_
