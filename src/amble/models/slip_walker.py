"""SLIP walker: a point mass walking on two massless spring legs, with a double-support phase.

The bipedal spring-mass model of walking of Geyer, Seyfarth & Blickhan 2006 ("Compliant leg
behaviour explains basic dynamics of walking and running", Proc. R. Soc. B 273:2861–2867): a
mass ``m`` on two massless legs, each a linear spring of stiffness ``k`` and rest length ``L0``.
A step is a directed cycle of two domains, single and double support::

        single support (u, w)             double support (u, w, d)
              o mass  \\                          o mass
              |        \\ swing leg              / \\
              |         (held at alpha)         /   \\
     _________o______________          ________o_____o________
         stance foot (origin)           rear foot     front foot, d ahead
                                         (origin)

* **single** (single support): ``u, w`` (m), the mass relative to the stance foot (Cartesian: the
  mass matrix is ``m I``). The stance spring's energy is ``k (L0 − sqrt(u² + w²))² / 2``. The
  swing leg is held at the angle of attack ``alpha``, measured from the horizontal ground with
  its foot ahead of the mass (Seyfarth's convention), and is drawn as the point ``swing_foot``.
* **touchdown** (single → double): the swing foot reaches the ground, ``w`` falling through
  ``L0 sin(alpha)``. The foot lands ``L0 cos(alpha)`` ahead of the mass: ``d = u + L0 cos(alpha)``.
  The legs are massless, so nothing is lost: positions and velocities are unchanged.
* **double** (double support): ``u, w`` (m), the mass relative to the rear foot (the origin), and
  ``d`` (m), the front foot's distance ahead of the rear foot. Both springs push on the mass. The
  front foot does not move: ``d`` is a held coordinate (``Model.hold``), set at touchdown with
  ``d_dot = 0`` and constant through the phase (its equation is ``d_ddot = 0``).
* **liftoff** (double → single): the rear spring's force ``k (L0 − l_rear)`` falls through zero,
  the rear leg back at its rest length; the front foot becomes the origin (``u → u − d``).
* **midstance** (single → single, the step of the return map): the vertical leg orientation,
  ``u`` rising through zero (the mass passing over the stance foot). The reset puts the state on
  the energy level ``energy`` (J) by the forward speed,
  ``u_dot = sqrt(2 (energy − m g w − k (L0 − w)² / 2) / m − w_dot²)``: the identity for a
  midstance on that level; without it the energy is a neutral direction, a multiplier 1.
* the mass reaching the ground, the stance leg unloading in single support (a flight phase: the
  gait is running, not walking), the front leg unloading before the rear one, or the mass
  stopping and falling back (``u_dot`` falling through zero) end the run (``fell``).

State order: single ``u, w, u_dot, w_dot``; double ``u, w, d, u_dot, w_dot, d_dot``. The Poincaré
section is the vertical leg orientation, ``(0, w, u_dot(w, w_dot), w_dot)``: its free
coordinates are the height ``w`` and the vertical velocity ``w_dot`` of the mass when it passes
over the stance foot. A symmetric walking gait has ``w_dot = 0`` there.

Parameters (Geyer et al. 2006's leg: 80 kg, 1 m, 20 kN/m; their walking energies are near 820 J):

==========  ==========  =====  =============================================================
name        default     unit   meaning
==========  ==========  =====  =============================================================
``m``       80          kg     body mass
``L0``      1.0         m      leg rest length
``k``       20000       N/m    leg stiffness (both legs)
``alpha``   69° = 1.204 rad    angle of attack from the horizontal, swing foot ahead of the mass
``g``       9.81        m/s²   gravity
``energy``  840         J      system energy, ``m g w + m v² / 2`` plus the springs' energy
==========  ==========  =====  =============================================================

At the defaults the walking gait passes midstance 0.990359 m high at 1.24335 m/s, steps 0.5456 m
in 0.41654 s (1.31 m/s on average), with a double support of 0.12214 s, and is stable: a complex
pair of multipliers 0.2621 ± 0.9179i (modulus 0.955). At 820 J the same leg and angle walk on a
symmetric gait that is just unstable (modulus 1.160); it becomes stable at 834.9 J. At 820 J a
softer leg walks stably (15 kN/m at 69°–72°: modulus between 0.85 and 0.97).
"""

from __future__ import annotations

import math

import sympy as sp

from amble import POSITIVE, Explicit, Guard, Model, Walker, interval

NAME = "slip-walker"
POSITION = 72  # place in `amble models` (ascending)

PARAMS = dict(m=80.0, L0=1.0, k=20000.0, alpha=math.radians(69.0), g=9.81, energy=840.0)


def _params(model: Model) -> tuple:
    out = model.parameters(**PARAMS)
    model.restrict("m L0 k g energy", POSITIVE)
    model.restrict("alpha", interval(0, math.pi / 2))
    return out


def _single() -> Model:
    s = Model("single")
    u, w = s.coordinates("u w", unit="m")
    m, L0, k, alpha, g, _ = _params(s)
    s.point("foot", (0, 0))
    s.point("mass", (u, w), mass=m, link="foot")
    s.point("swing_foot", (u + L0 * sp.cos(alpha), w - L0 * sp.sin(alpha)), link="mass")
    s.gravity(g)
    s.add_potential(k * (L0 - sp.sqrt(u**2 + w**2)) ** 2 / 2)
    return s


def _double() -> Model:
    dm = Model("double")
    u, w, d = dm.coordinates("u w d", unit="m")
    m, L0, k, _, g, _ = _params(dm)
    dm.point("foot", (0, 0))
    dm.point("mass", (u, w), mass=m, link="foot")
    dm.point("swing_foot", (d, 0), link="mass")
    dm.gravity(g)
    front = k * (L0 - sp.sqrt((u - d) ** 2 + w**2)) ** 2 / 2
    dm.add_potential(k * (L0 - sp.sqrt(u**2 + w**2)) ** 2 / 2 + front)
    # where the front foot landed: the ground holds it there for the whole phase
    dm.hold(d)
    return dm


def build(snap_to_energy: bool = True) -> Walker:
    """The walker. ``snap_to_energy=False`` leaves the midstance reset the identity: the run then
    carries its own energy from step to step."""
    si, do = _single(), _double()
    u, w = si.q
    ud, wd = si.qd
    m, L0, k, alpha, g, energy = (si.symbol(n) for n in PARAMS)
    s = Walker(NAME, {"single": si, "double": do}, hip="mass", max_step_time=10.0, doc=__doc__)
    s.transition("touchdown", "single", Guard(w - L0 * sp.sin(alpha), -1),
                 Explicit(q=[u, w, u + L0 * sp.cos(alpha)], qd=[ud, wd, 0]), "double")
    du, dw, dd = do.q
    dud, dwd, _ = do.qd
    rear, front = sp.sqrt(du**2 + dw**2), sp.sqrt((du - dd) ** 2 + dw**2)
    s.transition("liftoff", "double", Guard(k * (L0 - rear), -1),
                 Explicit(q=[du - dd, dw], qd=[dud, dwd], shift="swing_foot"), "single")
    speed = sp.sqrt(2 * (energy - m * g * w - k * (L0 - w) ** 2 / 2) / m - wd**2) if snap_to_energy else ud
    s.transition("midstance", "single", Guard(u, 1), Explicit(q=[0, w], qd=[speed, wd]), "single", step=True)
    s.terminal("fell", "single", Guard(w), status="fell")
    s.terminal("fell_in_double_support", "double", Guard(dw), status="fell")
    # the stance leg unloading in single support: a flight phase, running rather than walking
    s.terminal("flight", "single", Guard(k * (L0 - sp.sqrt(u**2 + w**2)), -1), status="fell")
    s.terminal("front_leg_unloads", "double", Guard(k * (L0 - front), -1), status="fell")
    s.terminal("falls_back", "single", Guard(ud, -1), status="fell")
    s.terminal("falls_back_in_double_support", "double", Guard(dud, -1), status="fell")
    # midstance 0.98 m high, level, on the default energy level (off the gait: the run settles)
    p = PARAMS
    w0 = 0.98
    u0 = math.sqrt(2 * (p["energy"] - p["m"] * p["g"] * w0 - p["k"] * (p["L0"] - w0) ** 2 / 2) / p["m"])
    s.default_start["single"] = [0.0, w0, u0, 0.0]
    s.fixed_point_guess = [0.0, 0.99, 1.24, 0.0]
    return s
