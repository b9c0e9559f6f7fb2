"""Kneed biped: a compass gait whose swing leg has a free knee until it locks (thesis 4.2, Table 3).

Coordinates: absolute angles from the vertical, foot → hip direction ``R(θ)``, positive leaning
downhill (+x), as in the compass gait. Mode "unlocked": ``stance, shank, thigh`` (swing shank
and thigh free); mode "locked": ``stance, thigh`` (swing knee straight, shank = thigh). The
stance leg is always straight. Each leg carries a shank mass ``ms`` and a thigh mass ``mt``::

                       hip (mh)
                      /    \\
          thigh mass o      o thigh mass, b2 below the hip
    (a2 above knee) /        \\
                   /          o swing knee
                  /           |
      shank mass o            o shank mass, b1 below the knee
    (a1 above   /             |
     the foot) /              |
     stance foot          swing foot       shank ls = a1 + b1, thigh lt = a2 + b2

A step: knee strike when ``shank − thigh`` falls through zero (the knee straightening, thesis
Eq. 27) — an impulsive lock (Eq. 28, derived) into "locked" — then heel strike of the straight
swing leg (plastic impact, derived) with the relabelling of Eq. 29 back to "unlocked" (new swing
shank = thigh = old stance). A heel strike with a bent knee ends the run ("scuffed"), as does
the hip reaching the ground ("fell"). The names are Hsu Chen's, so published sets drop in via
``params={...}`` / ``--set``: Hsu Chen 2007 ``mh=0.5 mt=0.5 ms=0.05 a1=0.375 b1=0.125 a2=0.175
b2=0.325 g=9.8 slope=0.0503685`` (her code's asin(7.25/144); her thesis prints 0.0504); McGeer
1990 in leg lengths ``mh=0.6885 mt=0.1 ms=0.062 a1=0.30 b1=0.24 a2=0.26 b2=0.20 It=0.0018225
Is=0.0021449 slope=0.0456`` (m·r_gyr² for ``It``, ``Is``; his round feet are not modelled).

Table 3 lists masses 10, 5, 3.5, 1.5 kg and pairs (a, b) = (.53, .47), (.35, .15), (.25, .25) m
with garbled labels. Its self-consistent reading: a 5 kg leg made of a 3.5 kg thigh whose mass
sits 0.35 m below the hip (0.15 m above the knee) and a 1.5 kg shank with its mass at mid-shank;
the leg's centre of mass is then (3.5·0.65 + 1.5·0.25)/5 = 0.53 m above the foot, 0.47 m below
the hip, as the first pair says. (The mirror reading, a 3.5 kg shank, also closes the balance
but puts more mass in the shank than in the thigh.) Defaults: ``mh`` 10, ``mt`` 3.5, ``ms``
1.5 kg; ``a1`` = ``b1`` = 0.25, ``a2`` 0.15, ``b2`` 0.35 m; ``It`` = ``Is`` = 0 kg·m² (segment
inertias about their mass centres: point masses); ``g`` 9.81 m/s²; ``slope`` 0.05 rad.

Stable gait at the defaults (post-impact): x* = (−0.22244, 0.32244, 0.32244, 1.09807, 0.55328,
0.55328) rad, rad/s; step 0.7327 s with the knee locking at 0.4248 s; multipliers 0.467 ± 0.518i
and 0.077. The thesis' Eq. 30, x* = (0.075, −0.081, −0.081, −0.26, 0.49, 0.49), has Goswami's
signs (angles counter-clockwise) at best, and lies on no heel-strike section of a 0.05 rad slope
(stance + swing would be ∓0.1): it cannot be compared beyond its signs.

At Hsu Chen's parameters the default search (``amble limit-cycle kneed-biped --set ...``) finds her
stable gait at slopes 0.0503685, 0.0504 and 0.06 (step 0.5646, 0.5646, 0.5754 s): it follows the
gait above from the defaults when the cycle nearest the guess is unstable (at 0.06: 0.474 s,
|multipliers| up to 3.60).
"""

from amble import NONNEGATIVE, POSITIVE, Guard, Model, R, Walker, heel_strike, height_above_slope, joint_lock

NAME = "kneed-biped"
POSITION = 20  # place in `amble models` (ascending)


def kneed_model(name: str, extra: str = "") -> Model:
    """The unlocked kneed walker (coordinates ``stance shank thigh``, then ``extra``)."""
    m = Model(name)
    st, sh, th, *_ = m.coordinates("stance shank thigh " + extra)
    mh, mt, ms, a1, b1, a2, b2, It, Is, g, slope = m.parameters(
        mh=10.0, mt=3.5, ms=1.5, a1=0.25, b1=0.25, a2=0.15, b2=0.35, It=0.0, Is=0.0, g=9.81, slope=0.05)
    m.restrict("mh mt ms a1 b1 a2 b2 g", POSITIVE)
    m.restrict("It Is", NONNEGATIVE)
    m.point("stance_foot", (0, 0))
    m.point("stance_shank", a1 * R(st), mass=ms)
    m.point("stance_thigh", (a1 + b1 + a2) * R(st), mass=mt)
    hip = m.point("hip", (a1 + b1 + a2 + b2) * R(st), mass=mh, link="stance_foot")
    m.point("swing_thigh", hip - b2 * R(th), mass=mt)
    knee = m.point("swing_knee", hip - (a2 + b2) * R(th), link="hip")
    m.point("swing_shank", knee - b1 * R(sh), mass=ms)
    m.point("swing_foot", knee - (a1 + b1) * R(sh), link="swing_knee")
    for angle, inertia in ((st, It + Is), (th, It), (sh, Is)):  # distributed mass (McGeer's gyration radii)
        m.inertia(angle, inertia)
    m.gravity(g)
    return m


def kneed_walker(m: Model, doc: str) -> Walker:
    """Modes "unlocked" and "locked" (knee straight: shank = thigh), the knee lock (Eq. 27–28),
    heel strike with the relabelling of Eq. 29, a bent-knee footfall ("scuffed") and falls."""
    (st, sh, th, *_), slope = m.q, m.symbol("slope")
    locked = m.constrained(f"{m.name}-locked", {sh: th})
    s = Walker(m.name, {"unlocked": m, "locked": locked}, hip="hip", slope=slope, doc=doc)
    s.transition("knee_lock", "unlocked", *joint_lock(sh - th), "locked")
    s.transition("heel_strike", "locked", *heel_strike(locked, "swing_foot", slope, {st: th, sh: st, th: st}),
                 "unlocked", step=True)
    s.terminal("scuffed", "unlocked", heel_strike(m, "swing_foot", slope, {})[0], status="scuffed")
    s.terminal("hip_on_ground", ["unlocked", "locked"], lambda mode: Guard(height_above_slope(mode, "hip", slope)))
    return s


def build() -> Walker:
    s = kneed_walker(kneed_model(NAME), __doc__)
    # the stable limit cycle at the defaults (post-impact state; step 0.7327 s, |multipliers| 0.697, 0.697, 0.077)
    s.default_start["unlocked"] = s.fixed_point_guess = [-0.2224446318, 0.3224446318, 0.3224446318, 1.098070999,
                                                         0.5532765919, 0.5532765919]
    return s
