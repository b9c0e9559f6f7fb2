"""Compass gait: two straight legs and a hip mass on a slope (thesis Section 4.1, Table 2).

Coordinates (Drake's convention, thesis Eq. 17–19)::

            hip (m_H)            stance: angle of the stance leg from the vertical,
            /  \\                         foot → hip, positive leaning downhill (+x)
     a   m /    \\ m   b         swing:  angle of the swing leg from the vertical,
          /      \\                       foot → hip, positive leaning downhill
    stance foot   swing foot     both legs: mass m at distance b from the foot (a from the hip)

State: ``stance, swing, stance_dot, swing_dot`` (rad, rad/s). The slope descends along +x at
``slope`` rad; heel strike when the swing foot reaches it ahead of the stance foot, then the
plastic impact (derived) and the swap of the legs. Parameters (Table 2): ``mh`` 10 kg, ``m`` 5 kg,
``a`` = ``b`` = 0.5 m, ``g`` 9.81 m/s², ``slope`` 0.05 rad.
"""

from amble import POSITIVE, Model, R, walker

NAME = "compass-gait"
POSITION = 10  # place in `amble models` (ascending)


def model(name: str = "compass-gait", slope: float = 0.05) -> Model:
    """The compass gait's mechanics (coordinates ``stance, swing``, Table 2's parameters, the
    ``slope`` parameter's default as given), before its walker is declared: actuated and controlled
    variants add inputs and laws to it."""
    m = Model(name)
    st, sw = m.coordinates("stance swing")
    mh, ml, a, b, g, _ = m.parameters(mh=10.0, m=5.0, a=0.5, b=0.5, g=9.81, slope=slope)
    m.restrict("mh m a b g", POSITIVE)
    m.point("stance_foot", (0, 0))
    hip = m.point("hip", (a + b) * R(st), mass=mh, link="stance_foot")
    m.point("stance_mass", b * R(st), mass=ml)
    m.point("swing_mass", hip - a * R(sw), mass=ml)
    m.point("swing_foot", hip - (a + b) * R(sw), link="hip")
    m.gravity(g)
    return m


def build():
    m = model()
    st, sw = m.q
    return walker(m, foot="swing_foot", hip="hip", slope=m.symbol("slope"), relabel={st: sw, sw: st},
                  start=[-0.2168, 0.3168, 1.0839, 0.3981], doc=__doc__)
