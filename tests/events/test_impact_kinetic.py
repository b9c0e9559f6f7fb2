"""Kinetic terms added with ``add_kinetic`` were silently left out of the
derived impact (the compass hip written as ``add_kinetic(½ m_H |ṗ_hip|²)`` gave post-impact rates
(0.982, 0.969) instead of (0.854, 0.500)). The expression cannot tell a translating mass from a
rotational inertia, so an Impact now rejects such terms with a ModelError that says why; rotational
inertia declared with ``inertia()`` enters the impact, checked against the conservation of
angular momentum about the impacting foot."""

import math

import numpy as np
import pytest
import sympy as sp

import amble
from amble import Model, R, walker
from amble.errors import ModelError


def _compass(name: str, hip_as_added_kinetic: bool = False, leg_inertia: float = 0.0):
    m = Model(name)
    st, sw = m.coordinates("stance swing")
    mh, ml, a, b, g, slope = m.parameters(mh=10.0, m=5.0, a=0.5, b=0.5, g=9.81, slope=0.05)
    m.point("stance_foot", (0, 0))
    if hip_as_added_kinetic:
        hip = m.point("hip", (a + b) * R(st), link="stance_foot")
        v = m.dt(hip)
        m.add_kinetic(sp.Rational(1, 2) * mh * (v.T * v)[0, 0])
        m.add_potential(mh * g * hip[1])
    else:
        hip = m.point("hip", (a + b) * R(st), mass=mh, link="stance_foot")
    m.point("stance_mass", b * R(st), mass=ml)
    m.point("swing_mass", hip - a * R(sw), mass=ml)
    m.point("swing_foot", hip - (a + b) * R(sw), link="hip")
    if leg_inertia:
        m.inertia(st, leg_inertia)
        m.inertia(sw, leg_inertia)
    m.gravity(g)
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st},
                  start=[-0.2168, 0.3168, 1.0839, 0.3981])


def test_added_kinetic_terms_are_rejected_by_an_impact():
    with pytest.raises(ModelError, match="add_kinetic"):
        amble.simulate(_compass("ev-kin-added", hip_as_added_kinetic=True), steps=1)


def _angular_momentum(x, about_origin_shift, mh=10.0, ml=5.0, a=0.5, b=0.5, inertia=0.0):
    """Angular momentum (y component, x-z plane) of the compass about a point, numerically."""
    st, sw, std, swd = x
    L = a + b
    r = lambda th: np.array([math.sin(th), math.cos(th)])  # noqa: E731
    dr = lambda th, w: w * np.array([math.cos(th), -math.sin(th)])  # noqa: E731
    hip, vhip = L * r(st), L * dr(st, std)
    pts = [(mh, hip, vhip), (ml, b * r(st), b * dr(st, std)), (ml, hip - a * r(sw), vhip - a * dr(sw, swd))]
    c = about_origin_shift
    h = sum(m * ((p - c)[0] * v[1] - (p - c)[1] * v[0]) for m, p, v in pts)
    return h - inertia * (std + swd)  # I θ̇ about −y for each leg, same sign convention as r × v


def test_rotational_inertia_enters_the_impact_conserving_angular_momentum():
    inertia = 0.3
    s = _compass("ev-kin-inertia", leg_inertia=inertia)
    tr = amble.simulate(s, steps=1)
    (ev,) = [e for e in tr.events if e.name == "heel_strike"]
    st, sw = ev.x_pre[:2]
    L = 1.0
    foot = L * np.array([math.sin(st), math.cos(st)]) - L * np.array([math.sin(sw), math.cos(sw)])
    h_pre = _angular_momentum(ev.x_pre, foot, inertia=inertia)
    h_post = _angular_momentum(ev.x_post, np.zeros(2), inertia=inertia)
    assert h_post == pytest.approx(h_pre, rel=1e-9, abs=1e-12)
