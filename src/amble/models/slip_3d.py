"""3D SLIP runner: a point mass on a massless spring leg, running in three dimensions.

The three-dimensional spring-loaded inverted pendulum of Seipel & Holmes 2005 ("Running in three
dimensions: analysis of a point-mass sprung-leg model", Int. J. Robotics Research 24(8):657–674):
the planar SLIP (``slip-runner``) with the leg free to point sideways, left and right legs
alternating. Their result: with the legs placed at fixed touchdown angles, every left–right
symmetric running gait is unstable, through its lateral motion. A stride is a directed cycle of
three domains, the same as the planar runner's:

* **descent** (flight after an apex): ``x, y, z`` (m), the mass's position; ``x`` forward (the
  mean direction of running), ``y`` to the side of this step's stance leg, ``z`` up; ``x, y``
  are measured from the last apex. Ballistic.
* **touchdown** (descent → stance): the leg touches the ground when ``z`` falls through
  ``L0 sin(alpha)``. **Leg placement rule**: at touchdown the foot is at
  ``mass + L0 (cos(alpha) cos(beta), cos(alpha) sin(beta), −sin(alpha))``: ``alpha`` is the
  leg's elevation from the horizontal ground (Seyfarth's angle of attack, as in
  ``slip-runner``), ``beta`` the azimuth of the leg's horizontal projection measured from the
  ``+x`` axis towards the stance side. Both angles are fixed in the world frame (relative to
  the mean direction of running, not to the mass's instantaneous heading) and the lateral one is
  mirrored every step: the left foot lands ``beta`` to the left of straight ahead, the right
  foot ``beta`` to the right. The foot becomes the origin; velocities are unchanged.
* **stance**: ``u, v, w`` (m), the mass relative to the foot (Cartesian, the mass matrix
  ``m I``). The spring's energy is ``k (L0 − sqrt(u² + v² + w²))² / 2``.
* **liftoff** (stance → ascent): the ground's normal force ``λ = k (L0 − l) w / l`` (N, ``l``
  the leg length) falls through zero: the leg is back at its rest length.
* **ascent** → **apex** (the step of the return map): ``z_dot`` falls through zero. The reset
  moves the origin under the mass and mirrors the lateral axis (``y → −y``: the other leg's
  side becomes ``+y``), so that one step is the return map of the left–right symmetric gait and
  a period-2 (left, right) gait is a fixed point. It also puts the state on the energy level
  ``E = m g z0 + m v0²/2`` by the forward speed, ``x_dot = sqrt(v0² + 2 g (z0 − z) − y_dot²)``
  (the identity for an apex on that level; without it the energy is a neutral direction, a
  multiplier 1). A run started at an apex, in ``descent``, steps at the next apex.
* the mass reaching the ground in stance, or a liftoff while still falling, ends the run
  (``fell``).

State order: flight ``x, y, z, x_dot, y_dot, z_dot``; stance ``u, v, w, u_dot, v_dot, w_dot``.
The Poincaré section is the apex ``(0, 0, z, x_dot, y_dot, 0)``: its free coordinates are the
apex height ``z`` and the lateral velocity ``y_dot`` (towards the coming stance foot when > 0).

Parameters (the planar runner's, Seyfarth et al. 2002, and a lateral angle of 5°):

=========  ==========  =====  ===========================================================
name       default     unit   meaning
=========  ==========  =====  ===========================================================
``m``      80          kg     body mass
``L0``     1.0         m      leg rest length
``k``      20000       N/m    leg stiffness
``alpha``  68° = 1.187 rad    leg elevation at touchdown, from the horizontal
``beta``   5° = 0.0873 rad    leg azimuth at touchdown, from straight ahead to the stance side
``g``      9.81        m/s²   gravity
``z0``     1.0         m      apex height that, with ``v0``, fixes the system energy
``v0``     5.0         m/s    horizontal speed at that apex
=========  ==========  =====  ===========================================================

At the defaults the symmetric gait has its apex at 0.939005 m with a lateral velocity of
0.04163 m/s towards the stance foot; its multipliers are −0.224 (apex height, the planar
runner's mode) and −1.213 (lateral velocity: the sideways fall). With ``beta = 0`` the gait is
``slip-runner``'s, with its multiplier −0.161 (self-stable) and besides it a lateral −1.211: even
the planar gait, run in three dimensions with its leg placed straight ahead, is laterally
unstable. Across the planar runner's self-stable band (16 kN/m at 66° to 28 kN/m at 70°) the
lateral multiplier lies between −1.17 and −1.31. Placing the leg relative to the mass's heading
instead would make the lateral multiplier exactly −1 (the model is then symmetric under rotations
about the vertical): neutral, not stable either. "Fixed touchdown angles" are read here as fixed
in the world frame, the rule under which the symmetric gaits are unstable as published.
"""

from __future__ import annotations

import math

import sympy as sp

from amble import POSITIVE, Explicit, Guard, Model, Walker, interval

NAME = "slip-3d"
POSITION = 71  # place in `amble models` (ascending)

PARAMS = dict(m=80.0, L0=1.0, k=20000.0, alpha=math.radians(68.0), beta=math.radians(5.0), g=9.81, z0=1.0,
              v0=5.0)


def _params(model: Model) -> tuple:
    out = model.parameters(**PARAMS)
    model.restrict("m L0 k g z0", POSITIVE)
    model.restrict("alpha", interval(0, math.pi / 2))
    model.restrict("beta", interval(-math.pi / 2, math.pi / 2))
    return out


def _leg(L0: sp.Expr, alpha: sp.Expr, beta: sp.Expr) -> sp.Matrix:
    """The foot relative to the mass at touchdown (m), in the step's frame."""
    return L0 * sp.Matrix([sp.cos(alpha) * sp.cos(beta), sp.cos(alpha) * sp.sin(beta), -sp.sin(alpha)])


def _flight(name: str) -> Model:
    fl = Model(name, dims=3)
    x, y, z = fl.coordinates("x y z", unit="m")
    m, L0, _, alpha, beta, g, *_ = _params(fl)
    mass = sp.Matrix([x, y, z])
    fl.point("ground", (x, y, 0))
    fl.point("mass", mass, mass=m)
    fl.point("foot", mass + _leg(L0, alpha, beta), link="mass")
    fl.gravity(g)
    return fl


def build(snap_to_energy: bool = True) -> Walker:
    """The runner. ``snap_to_energy=False`` leaves the apex reset a change of frame (origin under
    the mass, ``y → −y``) with the forward speed unchanged: the run then carries its own energy."""
    down, up = _flight("descent"), _flight("ascent")
    x, y, z = down.q
    xd, yd, zd = down.qd
    m, L0, k, alpha, beta, g, z0, v0 = (down.symbol(n) for n in PARAMS)

    st = Model("stance", dims=3)
    u, v, w = st.coordinates("u v w", unit="m")
    _params(st)
    st.point("foot", (0, 0, 0))
    st.point("mass", (u, v, w), mass=m, link="foot")
    st.gravity(g)
    leg = sp.sqrt(u**2 + v**2 + w**2)
    st.add_potential(k * (L0 - leg) ** 2 / 2)

    s = Walker(NAME, {"descent": down, "stance": st, "ascent": up}, hip="mass", mirror="y", max_step_time=10.0,
               doc=__doc__)
    # the foot lands at the fixed leg direction and becomes the origin; velocities are unchanged
    s.transition("touchdown", "descent", Guard(z - L0 * sp.sin(alpha), -1),
                 Explicit(q=list(-_leg(L0, alpha, beta)), qd=[xd, yd, zd], shift="foot"), "stance")
    normal_force = k * (L0 - leg) * w / leg  # the ground's push on the foot, N
    s.transition("liftoff", "stance", Guard(normal_force, -1), Explicit(q=[u, v, w], qd=list(st.qd)), "ascent")
    # the other leg next: mirror the lateral axis so that the step is the symmetric gait's return map
    speed = sp.sqrt(v0**2 + 2 * g * (z0 - z) - yd**2) if snap_to_energy else xd
    s.transition("apex", "ascent", Guard(zd, -1), Explicit(q=[0, 0, z], qd=[speed, -yd, 0], shift="ground"),
                 "descent", step=True)
    s.terminal("fell", "stance", Guard(w), status="fell")
    # lifting off while still falling: no flight phase, the leg would land again at once
    s.terminal("no_flight", "ascent", Guard(z - L0 * sp.sin(alpha)), status="fell")
    s.default_start["descent"] = [0.0, 0.0, PARAMS["z0"], PARAMS["v0"], 0.0, 0.0]
    # the symmetric gait at the defaults, to 1e-12: it is unstable, so a rougher guess walked for
    # the default guess's 30 steps would drift off sideways (|μ| = 1.21 per step)
    s.fixed_point_guess = [0.0, 0.0, 0.93900453048674, 5.11810493257634, 0.041629448565742, 0.0]
    return s
