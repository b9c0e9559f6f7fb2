"""SLIP runner: a point mass bouncing on a massless spring leg with a fixed angle of attack.

The spring-loaded inverted pendulum of Seyfarth, Geyer, Günther & Blickhan 2002 ("A movement
criterion for running", J. Biomech. 35:649–655): a mass ``m`` on a massless leg, a linear spring
of stiffness ``k`` and rest length ``L0``. A stride is a directed cycle of three domains::

        flight (x, y)                  stance (u, w): the mass relative to the foot
             o  mass                          o mass
            /                                /
           /  leg at alpha                  /  leg length sqrt(u² + w²)
          /   from the ground              /
    _____/_________________        _______o__________
        foot (in the air)               foot (the origin)

* **descent** (flight after an apex): ``x, y`` (m), the mass's position; ``x`` is measured from
  the last apex, ``y`` is the height above the ground. Ballistic.
* **touchdown** (descent → stance): the leg, held at the angle of attack ``alpha`` measured from
  the horizontal ground with the foot ahead of the mass (Seyfarth's convention), touches the
  ground when ``y`` falls through ``L0 sin(alpha)``; the foot is placed ``L0 cos(alpha)`` ahead
  of the mass and becomes the origin. The leg is massless, so nothing is lost: the reset only
  moves the origin, velocities are unchanged.
* **stance**: ``u, w`` (m), the mass relative to the foot (Cartesian: the mass matrix is ``m I``
  everywhere, where polar coordinates about the foot would be singular at zero leg length).
  The spring's energy is ``k (L0 − sqrt(u² + w²))² / 2``.
* **liftoff** (stance → ascent): the ground's normal force ``λ = k (L0 − l) w / l`` (N, ``l`` the
  leg length) falls through zero. For a massless spring leg the force on the ground is the
  spring force along the leg, so ``λ = 0`` is the leg back at its rest length.
* **ascent** (flight before the apex) → **apex** (ascent → descent, the step of the return map):
  ``y_dot`` falls through zero. The reset moves the origin under the mass (``x → 0``: ``x`` is
  cyclic) and puts the state on the energy level ``E = m g y0 + m v0²/2``:
  ``x_dot = sqrt(v0² + 2 g (y0 − y))``, which is the identity for an apex of a run on that level
  and reduces the return map to Seyfarth's one-dimensional apex-height map (the energy would
  otherwise be a neutral direction, a multiplier 1). The run's energy is set by ``y0`` and
  ``v0``: start it on that level. A run started at an apex, in ``descent``, takes it as its
  first section point and steps at the next apex.
* the mass reaching the ground in stance, or a liftoff while still falling (no flight phase),
  ends the run (``fell``).

State order: flight ``x, y, x_dot, y_dot``; stance ``u, w, u_dot, w_dot``. The Poincaré
section is the apex, ``(0, y, x_dot(y), 0)``: apex height ``y`` → next apex height.

Parameters (Seyfarth et al. 2002: 80 kg, 1 m leg, 20 kN/m, 68°, an apex 1 m high at 5 m/s):

=========  ==========  =====  ===========================================================
name       default     unit   meaning
=========  ==========  =====  ===========================================================
``m``      80          kg     body mass
``L0``     1.0         m      leg rest length
``k``      20000       N/m    leg stiffness
``alpha``  68° = 1.187 rad    angle of attack from the horizontal, foot ahead of the mass
``g``      9.81        m/s²   gravity
``y0``     1.0         m      apex height that, with ``v0``, fixes the system energy
``v0``     5.0         m/s    forward speed at that apex
=========  ==========  =====  ===========================================================

At the defaults the self-stable gait has its apex at 0.94027 m (forward speed 5.1144 m/s),
multiplier −0.161; the angle of attack gives self-stable running in a band of about 1.5°
(67–68.5° at 20 kN/m and this energy), as Seyfarth et al. found.
"""

from __future__ import annotations

import math

import sympy as sp

from amble import POSITIVE, Explicit, Guard, HybridSystem, Model, interval

NAME = "slip-runner"
POSITION = 70  # place in `amble models` (ascending)

PARAMS = dict(m=80.0, L0=1.0, k=20000.0, alpha=math.radians(68.0), g=9.81, y0=1.0, v0=5.0)


def _params(model: Model) -> tuple:
    out = model.parameters(**PARAMS)
    model.restrict("m L0 k g y0", POSITIVE)
    model.restrict("alpha", interval(0, math.pi / 2))
    return out


def _flight(name: str) -> Model:
    fl = Model(name)
    x, y = fl.coordinates("x y", unit="m")
    m, L0, _, alpha, g, *_ = _params(fl)
    fl.point("ground", (x, 0))
    fl.point("mass", (x, y), mass=m)
    fl.point("foot", (x + L0 * sp.cos(alpha), y - L0 * sp.sin(alpha)), link="mass")
    fl.gravity(g)
    return fl


def build(snap_to_energy: bool = True) -> HybridSystem:
    """The runner. ``snap_to_energy=False`` leaves the apex reset as a pure change of origin (the
    forward speed unchanged): the run then carries its own energy from stride to stride."""
    down, up = _flight("descent"), _flight("ascent")
    x, y = down.q
    xd, yd = down.qd
    m, L0, k, alpha, g, y0, v0 = (down.symbol(n) for n in PARAMS)

    st = Model("stance")
    u, w = st.coordinates("u w", unit="m")
    _params(st)
    st.point("foot", (0, 0))
    st.point("mass", (u, w), mass=m, link="foot")
    st.gravity(g)
    leg = sp.sqrt(u**2 + w**2)
    st.add_potential(k * (L0 - leg) ** 2 / 2)

    s = HybridSystem(NAME, {"descent": down, "stance": st, "ascent": up}, max_step_time=10.0, doc=__doc__)
    # the foot lands L0 cos(alpha) ahead of the mass and becomes the origin; velocities are unchanged
    s.transition("touchdown", "descent", Guard(y - L0 * sp.sin(alpha), -1),
                 Explicit(q=[-L0 * sp.cos(alpha), y], qd=[xd, yd], shift="foot"), "stance")
    normal_force = k * (L0 - leg) * w / leg  # the ground's push on the foot, N
    s.transition("liftoff", "stance", Guard(normal_force, -1),
                 Explicit(q=[u, w], qd=list(st.qd)), "ascent")
    speed = sp.sqrt(v0**2 + 2 * g * (y0 - y)) if snap_to_energy else xd
    s.transition("apex", "ascent", Guard(yd, -1), Explicit(q=[0, y], qd=[speed, 0], shift="ground"), "descent",
                 step=True)
    s.terminal("fell", "stance", Guard(w), status="fell")
    # lifting off while still falling: no flight phase, the leg would land again at once
    s.terminal("no_flight", "ascent", Guard(y - L0 * sp.sin(alpha)), status="fell")
    s.default_start["descent"] = [0.0, PARAMS["y0"], PARAMS["v0"], 0.0]
    s.fixed_point_guess = [0.0, 0.94, math.sqrt(25 + 2 * 9.81 * 0.06), 0.0]
    return s
