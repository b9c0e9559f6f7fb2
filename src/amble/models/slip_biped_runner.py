"""Bipedal SLIP runner with swing-leg retraction: two spring legs taking turns, flight between.

The bipedal spring-mass model of running (Geyer, Seyfarth & Blickhan 2006) with the leg-placement
control of Seyfarth, Geyer & Herr 2003 ("Swing-leg retraction: a simple control model for stable
running", J. Exp. Biol. 206:2547–2555): a mass ``m`` on two massless legs, each a linear spring
of stiffness ``k`` and rest length ``L0``. The legs alternate, one on the ground at a time, with
a flight phase between stances: flight → stance on one leg → flight → stance on the other → …
The legs being massless and alike, a step (apex to apex) is the same map whichever leg lands,
and the legs are relabelled at every apex: a symmetric (left, right) running gait is a fixed
point of the one-step map. A step is a directed cycle of three domains::

        descent (x, y, phi)            stance (u, w)                 ascent (x, y, phi)
             o mass                       o mass                        o mass
            / \\                           |\\  swing leg, folded          / \\
   trailing/   \\ landing leg at phi        | o                 lifted  /   \\ swing leg,
    leg   o     o (turning back at         |                     leg  o     o forward to alpha
                   omega: retraction)   ___o________                       at the apex
    ______________________             foot (origin)        ____________________

* **descent** (flight after an apex): ``x, y`` (m), the mass's position; ``x`` is measured from
  the apex, ``y`` is the height above the ground. Ballistic. ``phi`` (rad): the landing leg's
  angle from the horizontal ground, its foot ahead of the mass (Seyfarth's angle of attack). **Leg
  placement (swing-leg retraction)**: the leg turns backwards at the constant rate ``omega``
  from the angle ``alpha`` it has at the apex, ``phi = alpha + omega (t − t_apex)``: a held
  coordinate (``Model.hold``) that the apex sets to ``alpha`` with the velocity ``omega``. A
  higher apex falls for longer, so its leg lands steeper: that is the stabilising feedback. The
  other leg trails, drawn mirrored behind the mass.
* **touchdown** (descent → stance): the landing foot reaches the ground, ``y`` falling through
  ``L0 sin(phi)``; the foot lands ``L0 cos(phi)`` ahead of the mass and becomes the origin. The
  legs are massless, so nothing is lost: velocities are unchanged.
* **stance**: ``u, w`` (m), the mass relative to the stance foot (Cartesian: the mass matrix is
  ``m I``). The spring's energy is ``k (L0 − l)² / 2``, ``l = sqrt(u² + w²)``. The swing leg,
  drawn as the stance leg mirrored about the vertical and folded to the length ``l² / L0``,
  goes from trailing to leading.
* **liftoff** (stance → ascent): the ground's normal force ``λ = k (L0 − l) w / l`` (N) falls
  through zero: the leg is back at its rest length.
* **ascent** (flight before the apex): ``x, y`` (m) measured from the lifted foot, ``phi`` (rad)
  the swinging leg's angle ahead of the mass, turning at a constant rate from the lifted leg's
  mirror image at lift-off to ``alpha`` at the apex (drawing only: no event depends on it).
* **apex** (ascent → descent, the step of the return map): ``y_dot`` falls through zero. The
  swing leg becomes the landing leg (the relabelling of a step), the origin moves under the mass
  (``x → 0``) and the state is put on the energy level ``E = m g y0 + m v0²/2`` by the forward
  speed, ``x_dot = sqrt(v0² + 2 g (y0 − y))``: the identity for an apex on that level, which
  reduces the return map to the one-dimensional apex-height map (the energy would otherwise be a
  neutral direction, a multiplier 1). A run started at an apex, in ``descent``, steps at the next
  apex.
* the mass reaching the ground ends the run (``fell``).

State order: flight ``x, y, phi, x_dot, y_dot, phi_dot``; stance ``u, w, u_dot, w_dot``. The
Poincaré section is the apex, ``(0, y, alpha, x_dot(y), 0, omega)``: apex height ``y`` → next
apex height.

Parameters (Seyfarth et al.'s leg, 80 kg, 1 m, 20 kN/m, at 5 m/s with an apex 1.1 m high):

=========  ============  =====  ===========================================================
name       default       unit   meaning
=========  ============  =====  ===========================================================
``m``      80            kg     body mass
``L0``     1.0           m      leg rest length (both legs)
``k``      20000         N/m    leg stiffness (both legs)
``alpha``  52° = 0.9076  rad    the landing leg's angle at the apex, from the horizontal
``omega``  60°/s = 1.047 rad/s  retraction rate of the landing leg in flight (0: a fixed angle)
``g``      9.81          m/s²   gravity
``y0``     1.1           m      apex height that, with ``v0``, fixes the system energy
``v0``     5.0           m/s    forward speed at that apex
=========  ============  =====  ===========================================================

At the defaults the running gait has its apex 1.183449 m high (forward speed 4.8335 m/s) and
steps 3.0772 m in 0.64686 s; the leg lands at 66.063° after 0.2344 s of descent, the stance lasts
0.1781 s and the flight phases (lift-off to touchdown) 0.4688 s of the step. Its multiplier is
−0.0387: the retraction makes it nearly deadbeat. The same gait run with the leg held fixed at
its touchdown angle (``alpha`` = 66.063°, ``omega = 0``: the same trajectory) is unstable,
multiplier +1.321: the stability is the controller's. Without retraction at the default
``alpha`` = 52° there is no running gait at all: every apex is followed by a higher one.
"""

from __future__ import annotations

import math

import sympy as sp

from amble import POSITIVE, Explicit, Guard, Model, Walker, interval

NAME = "slip-biped-runner"
POSITION = 73  # place in `amble models` (ascending)

PARAMS = dict(m=80.0, L0=1.0, k=20000.0, alpha=math.radians(52.0), omega=math.radians(60.0), g=9.81, y0=1.1,
              v0=5.0)
#: the running gait at the defaults (apex height, m), to 1e-12
APEX = 1.18344867153385


def _params(model: Model) -> tuple:
    out = model.parameters(**PARAMS)
    model.restrict("m L0 k g y0", POSITIVE)
    model.restrict("alpha", interval(0, math.pi / 2))
    return out


def _flight(name: str, landing: str, trailing: str) -> Model:
    """A flight domain: the mass at ``(x, y)``, the leg ahead (``landing``) at ``phi`` below the
    horizontal and the other (``trailing``) mirrored behind; ``phi`` held (it turns at the rate
    the entering reset gives it)."""
    fl = Model(name)
    x, y = fl.coordinates("x y", unit="m")
    (phi,) = fl.coordinates("phi", unit="rad")
    m, L0, *_, g, _, _ = _params(fl)
    fl.point("ground", (x, 0))
    fl.point("mass", (x, y), mass=m)
    fl.point(landing, (x + L0 * sp.cos(phi), y - L0 * sp.sin(phi)))
    fl.point(trailing, (x - L0 * sp.cos(phi), y - L0 * sp.sin(phi)))
    fl.link("foot", "mass")
    fl.link("mass", "swing_foot")
    fl.gravity(g)
    fl.hold(phi)
    return fl


def build(snap_to_energy: bool = True) -> Walker:
    """The runner. ``snap_to_energy=False`` leaves the apex reset a change of origin with the
    forward speed unchanged: the run then carries its own energy from step to step."""
    # the leg that lands in this step is "foot" throughout the step, the other "swing_foot"
    down, up = _flight("descent", "foot", "swing_foot"), _flight("ascent", "swing_foot", "foot")
    x, y, phi = down.q
    xd, yd, _ = down.qd
    m, L0, k, alpha, omega, g, y0, v0 = (down.symbol(n) for n in PARAMS)

    st = Model("stance")
    u, w = st.coordinates("u w", unit="m")
    _params(st)
    leg = sp.sqrt(u**2 + w**2)
    st.point("ground", (u, 0))  # under the mass, as in flight
    st.point("foot", (0, 0))
    st.point("mass", (u, w), mass=m, link="foot")
    # the swing leg: the stance leg mirrored about the vertical, folded to l²/L0 (off the ground)
    st.point("swing_foot", (u + u * leg / L0, w - w * leg / L0), link="mass")
    st.gravity(g)
    st.add_potential(k * (L0 - leg) ** 2 / 2)
    ud, wd = st.qd

    s = Walker(NAME, {"descent": down, "stance": st, "ascent": up}, hip="mass", max_step_time=10.0, doc=__doc__)
    # the landing foot reaches the ground L0 cos(phi) ahead of the mass and becomes the origin
    s.transition("touchdown", "descent", Guard(y - L0 * sp.sin(phi), -1),
                 Explicit(q=[-L0 * sp.cos(phi), y], qd=[xd, yd], shift="foot"), "stance")
    normal_force = k * (L0 - leg) * w / leg  # the ground's push on the foot, N
    # the swing leg, at the lifted leg's mirror image, turns to reach alpha at the apex (w_dot / g away)
    lifted = sp.atan2(w, u)
    s.transition("liftoff", "stance", Guard(normal_force, -1),
                 Explicit(q=[u, w, lifted], qd=[ud, wd, (alpha - lifted) * g / wd]), "ascent")
    # the same symbols in ascent: the apex reads the ascent's state
    speed = sp.sqrt(v0**2 + 2 * g * (y0 - y)) if snap_to_energy else xd
    s.transition("apex", "ascent", Guard(yd, -1), Explicit(q=[0, y, alpha], qd=[speed, 0, omega], shift="ground"),
                 "descent", step=True)
    s.terminal("fell", "stance", Guard(w), status="fell")
    s.terminal("fell_in_descent", "descent", Guard(y), status="fell")
    # a lift-off while still falling has no apex: the mass falls to the ground
    s.terminal("fell_in_ascent", "ascent", Guard(y), status="fell")
    p = PARAMS
    s.default_start["descent"] = [0.0, p["y0"], p["alpha"], p["v0"], 0.0, p["omega"]]
    s.fixed_point_guess = [0.0, APEX, p["alpha"], math.sqrt(p["v0"] ** 2 + 2 * p["g"] * (p["y0"] - APEX)), 0.0,
                           p["omega"]]
    return s
