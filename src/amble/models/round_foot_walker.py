"""Round-foot walker: McGeer's passive walker with straight legs and round feet (McGeer 1990).

Coordinates (as the compass gait, Drake's convention): ``stance`` and ``swing`` are the angles
of the legs from the vertical, foot → hip, positive leaning downhill (+x)::

               hip (mh)
               /  \\            each leg: mass m at c from the hip, moment of inertia I
            c /    \\           about that centre of mass; its foot an arc of radius r
        m, I o      o m, I      centred l from the hip, on the leg
            /        \\
           /          \\
          ( )         ( )      the stance foot rolls without slip: its contact advances
    ------------------------   r·Δθ down the slope as the leg turns by Δθ

State: ``stance, swing, stance_dot, swing_dot`` (rad, rad/s). The origin of each step's frame is
the point of the slope that the stance foot touches when the stance leg is normal to the slope
(``stance = slope``); the contact point moves along the slope from there as the foot rolls.
Heel strike when the swing foot's arc reaches the slope ahead of the stance foot's contact (for
equal legs: ``stance + swing = 2·slope``, as with point feet). The impact is plastic, without
slip, on the material point of the swing foot at the contact (derived; the old stance foot
lifts off): it conserves the whole walker's angular momentum about that point and the trailing
leg's about the hip. Then the legs swap. Points: ``hip``, ``stance_mass``, ``swing_mass``, and for
each foot its contact (``stance_foot``, ``swing_foot``), ``…_centre`` and ``…_rolling`` (see
:func:`amble.round_foot`).

Parameters (defaults: a leg of total length l + r = 1 m, its mass a 5 kg uniform rod between
the hip and the foot's arc centre, a hip mass of 10 kg as in the compass gait):

=========  =======  ======  ====================================================
name       default  unit    meaning
=========  =======  ======  ====================================================
``mh``     10       kg      hip point mass (may be 0)
``m``      5        kg      mass of each leg
``I``      0.2042   kg·m²   each leg's moment of inertia about its centre of mass (≈ m l²/12)
``l``      0.7      m       hip to the centre of the foot's arc
``c``      0.35     m       hip to the leg's centre of mass, along the leg
``r``      0.3      m       foot radius
``g``      9.81     m/s²    gravity
``slope``  0.05     rad     slope of the ground
=========  =======  ======  ====================================================

With ``r = 0``, ``I = 0``, ``l = a + b`` and ``c = a`` it is the compass gait (thesis Table 2).
Stable gait at the defaults (post-impact): x* = (−0.344247, 0.444247, 1.385634, 0.368216) rad,
rad/s; step 0.74061 s; multipliers 0.1554 ± 0.4837i and 0.1353.
"""

from amble import NONNEGATIVE, POSITIVE, Model, R, rolling_centre, round_foot, walker

NAME = "round-foot-walker"
POSITION = 65  # place in `amble models` (ascending)


def build():
    m = Model("round-foot-walker")
    st, sw = m.coordinates("stance swing")
    mh, ml, I, l, c, r, g, slope = m.parameters(mh=10.0, m=5.0, I=0.2042, l=0.7, c=0.35, r=0.3, g=9.81,
                                                slope=0.05)
    m.restrict("m l g", POSITIVE)
    m.restrict("mh I c r", NONNEGATIVE)
    stance = round_foot(m, "stance_foot", rolling_centre(st, r, slope), st, r, slope)
    hip = m.point("hip", m.points[stance.centre] + l * R(st), mass=mh, link=stance.centre)
    m.point("stance_mass", hip - c * R(st), mass=ml)
    m.point("swing_mass", hip - c * R(sw), mass=ml)
    swing = round_foot(m, "swing_foot", hip - l * R(sw), sw, r, slope, link="hip")
    m.inertia(st, I)
    m.inertia(sw, I)
    m.gravity(g)
    return walker(m, foot=swing, stance=stance, hip="hip", slope=slope, relabel={st: sw, sw: st},
                  start=[-0.3442470356, 0.4442470356, 1.385633677, 0.3682157157], doc=__doc__)
