"""Humanoid in 2D: the kneed biped with a controlled torso above the hip (thesis 4.3, Table 4).

Coordinates: those of :mod:`amble.models.kneed_biped` plus ``torso``, the absolute angle of the
torso from the vertical (hip → torso mass, positive leaning downhill (+x)), in both modes::

        o  torso mass m_T          torso: an inverted pendulum of length l_T on the hip
        |  l_T                     mode "unlocked": stance, shank, thigh, torso
      hip (m_H)                    mode "locked":   stance, swing, torso
       /  \\   the kneed biped below (see kneed-biped)

Control (thesis Eq. 33–35): a PD torque ``τ = k_T (θ_d − torso) − k_v torso_dot`` (Eq. 34)
between torso and stance leg (the stance leg takes the reaction), and a torque
``τ_2 = −k_leg L`` on the swing leg (on its thigh while the knee is free) while the step length
``L = −x(swing foot) > 0`` (Eq. 35: the swing foot is behind the stance foot), zero otherwise;
like the thesis' Γ it has no reaction. Knee lock, heel strike (the torso angle is kept) and
falls as in the kneed biped.

Parameters: the kneed biped's (Table 3 reading) and ``mT`` 3 kg (Table 4); ``lT`` 0.5 m, hip to
torso mass (Table 4's 5 m torso is implausible over a 1 m leg: read as 0.5 m); gains ``kT``
100 N·m/rad, ``kv`` 10 N·m·s/rad, ``theta_d`` 0 rad (upright), ``kleg`` 5 N·m/m. Without the
step-length torque (``kleg`` 0) the fixed-point search from this gait does not converge;
``kleg`` 2–5 gives stable gaits, ``kleg`` 10 an unstable one.

Stable gait at the defaults (post-impact; stance, shank, thigh, torso, then rates): x* =
(−0.22061, 0.32061, 0.32061, −0.04424, 0.97088, 0.41058, 0.41058, 0.46373); step 0.7827 s;
multipliers −0.325 ± 0.198i, 0.122, 0.0017, 0.0011. (Thesis Eq. 36 repeats the kneed biped's
x* with torso (0.03, 0.05): not comparable, see kneed-biped.)
"""

import sympy as sp

from amble import NONNEGATIVE, POSITIVE, R, Walker
from amble.models.kneed_biped import kneed_model, kneed_walker

NAME = "humanoid-2d"
POSITION = 30  # place in `amble models` (ascending)


def build() -> Walker:
    m = kneed_model(NAME, "torso")
    st, sh, th, tr = m.q
    mT, lT, kT, kv, theta_d, kleg = m.parameters(mT=3.0, lT=0.5, kT=100.0, kv=10.0, theta_d=0.0, kleg=5.0)
    m.restrict("mT lT", POSITIVE)
    m.restrict("kT kv kleg", NONNEGATIVE)
    m.point("torso", m.points["hip"] + lT * R(tr), mass=mT, link="hip")
    m.torque(kT * (theta_d - tr) - kv * m.dot(tr), tr - st)  # Eq. 34, reacting on the stance leg
    step_length = -m.points["swing_foot"][0]  # Eq. 35: positive while the swing foot is behind
    m.torque(sp.Piecewise((-kleg * step_length, step_length > 0), (0, True)), th)
    s = kneed_walker(m, __doc__)
    # the stable limit cycle at the defaults (post-impact state; step 0.7827 s, |multipliers| ≤ 0.381)
    s.default_start["unlocked"] = s.fixed_point_guess = [-0.2206099995, 0.3206099995, 0.3206099995, -0.0442356769,
                                                         0.9708804245, 0.4105759175, 0.4105759175, 0.4637318092]
    return s
