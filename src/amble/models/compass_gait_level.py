"""Compass gait on level ground under controlled symmetry (Spong & Bullo 2005).

It walks the passive gait of a slope it only emulates.

The model is the compass gait of Section 4.1 (Table 2 parameters; coordinates as in
``compass-gait``: absolute leg angles from the vertical, foot → hip, positive forward) with two
inputs — an ankle torque on the stance angle and a hip torque between the legs, so
``B = [[−1, 1], [1, 0]]`` (rows: stance, swing; columns: hip, ankle) is invertible — and the
ground's ``slope`` 0. Turning every absolute angle by ``γ`` leaves the kinetic energy and the
impact unchanged (they depend on the angle between the legs only) but turns gravity; the law

    B u = ∂V/∂q (q) − ∂V/∂q (q + γ·1),        γ = ``emulated_slope`` (rad),

replaces the potential by ``V(q + γ·1)``, the potential of the walker on a slope ``γ`` written in
angles from the slope's normal. The closed loop on level ground is therefore the passive walker
on that slope turned by ``γ``: its gait has the passive fixed point with both angles less ``γ``,
the same velocities, step time and multipliers. ``emulated_slope`` 0.05 rad (the passive
model's slope); ``slope`` stays a parameter (the closed loop on a slope ``s`` walks the gait of
``s + γ``).
"""

import sympy as sp

from amble import walker
from amble.models import compass_gait

NAME = "compass-gait-level"
POSITION = 45  # after the thesis models


def build():
    m = compass_gait.model("compass-gait-level", slope=0.0)
    st, sw = m.q
    slope = m.symbol("slope")
    gamma = m.parameter("emulated_slope", 0.05, "slope whose passive gait the controller reproduces", "rad")
    u_hip = m.actuator("hip", on=sw - st)
    u_ankle = m.actuator("ankle", on=st)
    V = m.V
    turned = {st: st + gamma, sw: sw + gamma}
    shaping = sp.Matrix([sp.diff(V, q) - sp.diff(V, q).xreplace(turned) for q in (st, sw)])
    u = m.input_matrix().inv() * shaping
    m.control({u_hip: u[0], u_ankle: u[1]})
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel={st: sw, sw: st},
                  start=[-0.2668, 0.2668, 1.0839, 0.3981], doc=__doc__)
