"""Humanoid in 3D as in the thesis (Section 4.4, Eq. 37–40, Tables 3/4): humanoid-2d with coronal angles.

Seven coordinates (absolute angles; a link direction is ``R3(Θ, Φ)`` of Eq. 37, Θ > 0 leaning
downhill (+x), Φ > 0 leaning to +y), in the order of Eq. 40's Γ::

        o torso (m_T)       stance, stance_cor:  Θ, Φ of the stance leg, foot → hip
        |  l_T              thigh, shank:        Θ of the swing thigh and shank, hip → foot
       hip (m_H)            swing_cor:           Φ of the swing leg (thigh and shank share it)
       /   \\               torso, torso_cor:    Θ, Φ of the torso, hip → torso mass
  stance    swing thigh, knee, swing shank       mode "locked" (knee straight): shank = thigh

Legs, knee lock and heel strike are humanoid-2d's, lifted into 3D: the thigh and the shank of the
swing leg share the coronal angle, so the knee is a hinge about the step frame's y axis and the
knee lock (``shank − thigh`` falling through zero, Section 4.2, adopted unchanged) is one scalar
constraint, derived as an impulsive ``Lock``. The heel strike is amble's full 3D plastic impact of
the straight swing foot (floating base with three translations, a three-component impulse),
followed by the swap of the legs and ``y → −y`` (``mirror="y"``): Θ's swap, Φ's swap with a sign
flip, the torso's Φ changes sign. All legs and the torso hang from the one hip point m_H, and each
is a chain of point masses along a direction with two angles: a rigid rotation of the whole robot
about any axis through the impact point is therefore a motion of the model (in mode "locked",
where heel strike happens), so the derived impact conserves all three components of the angular
momentum about the new stance foot — no eighth coordinate is needed. (A pelvis of non-zero width
would need one: its orientation about the vertical, see humanoid-3d-yaw.) At the knee lock the
thigh and shank are aligned, so rotations about the stance foot, and of the swing leg about the
hip, are motions of the model too: the lock conserves the whole robot's angular momentum about
the stance foot and the swing leg's about the hip, in all three components.

Parameters, read from Tables 3/4 exactly as kneed-biped and humanoid-2d read them (same names and
defaults): each leg is a 3.5 kg thigh (``mt``) with its mass 0.35 m below the hip (``b2``; 0.15 m
above the knee, ``a2``) and a 1.5 kg shank (``ms``) with its mass at mid-shank (``a1`` = ``b1`` =
0.25 m) — the stance leg carries the same two masses, so the 5 kg leg (m_1) has its centre of mass
0.53 m above the foot and 0.47 m below the hip, Table 3's first pair; ``mh`` 10 kg; ``mT`` 3 kg and
``lT`` 0.5 m (Table 4's "5" read as 0.5 m); ``g`` 9.81 m/s²; ``slope`` 0.05 rad. Point masses (no
segment inertias). With every Φ and Φ̇ zero the model is humanoid-2d exactly.

Control Γ (Eq. 40, entries in the coordinate order above): stance 0; stance_cor (τ_2), swing_cor
(τ_5), torso_cor (τ_7): spring-dampers ``−k Φ − k_v Φ̇`` (the ``τ_i = k_i θ_i + k_vi θ̇_i`` of
Eq. 40, signs chosen to restore): ``k_sc`` 200 N·m/rad, ``kv_sc`` 40 N·m·s/rad (below k_sc ≈ 71
a real multiplier of the sideways fall of the stance leg leaves the unit circle: −1.13 at 60,
|μ| = 2.06 at 0), ``k_sw`` 50,
``kv_sw`` 10, ``k_tc`` 100, ``kv_tc`` 10; torso (τ_6): humanoid-2d's PD ``kT (theta_d − torso) −
kv torso_dot`` (``kT`` 100, ``kv`` 10, ``theta_d`` 0), between torso and stance leg as in
humanoid-2d (the stance leg takes the reaction); thigh: humanoid-2d's step-length torque ``−kleg·L``
while ``L > 0`` (``kleg`` 5 N·m/m; Eq. 40 prints 0 there, but the text keeps the 2D step-length
controller, and without it the sagittal gait has no fixed point, see humanoid-2d). ``kleg = 0``
and all coronal gains 0 give the uncontrolled (conservative between impacts) robot.

State (mode "unlocked"): ``stance stance_cor thigh shank swing_cor torso torso_cor`` then rates.
Stable gait at the defaults (post-impact): humanoid-2d's gait with the coronal angles at zero,
x* = (−0.22061, 0, 0.32061, 0.32061, 0, −0.04424, 0, 0.97088, 0, 0.41058, 0.41058, 0, 0.46373, 0);
step 0.7827 s, the knee locking before heel strike — the thesis' remark that the 3D fixed points
equal the 2D ones holds exactly for this left–right symmetric model. Multipliers: humanoid-2d's
−0.325 ± 0.198i and 0.122, and the coronal modes' −0.192, 0.179, 0.011, … (all inside).
"""

import sympy as sp

from amble import NONNEGATIVE, POSITIVE, R3, Guard, Model, Walker, heel_strike, height_above_slope, joint_lock

NAME = "humanoid-3d"
POSITION = 40  # place in `amble models` (ascending)

#: humanoid-2d's stable gait (post-impact), coronal angles and rates zero
_GAIT_2D = [-0.2206099995, 0.3206099995, 0.3206099995, -0.0442356769,
            0.9708804245, 0.4105759175, 0.4105759175, 0.4637318092]


def build() -> Walker:
    m = Model(NAME, dims=3)
    st, st_c, th, sh, sw_c, tor, tor_c = m.coordinates("stance stance_cor thigh shank swing_cor torso torso_cor")
    mh, mt, ms, a1, b1, a2, b2, mT, lT, g, slope = m.parameters(
        mh=10.0, mt=3.5, ms=1.5, a1=0.25, b1=0.25, a2=0.15, b2=0.35, mT=3.0, lT=0.5, g=9.81, slope=0.05)
    kT, kv, theta_d, kleg = m.parameters(kT=100.0, kv=10.0, theta_d=0.0, kleg=5.0)
    k_sc, kv_sc, k_sw, kv_sw, k_tc, kv_tc = m.parameters(
        k_sc=200.0, kv_sc=40.0, k_sw=50.0, kv_sw=10.0, k_tc=100.0, kv_tc=10.0)
    m.restrict("mh mt ms a1 b1 a2 b2 mT lT g", POSITIVE)
    m.restrict("kT kv kleg k_sc kv_sc k_sw kv_sw k_tc kv_tc", NONNEGATIVE)
    up = R3(st, st_c)
    m.point("stance_foot", (0, 0, 0))
    m.point("stance_shank", a1 * up, mass=ms)
    m.point("stance_thigh", (a1 + b1 + a2) * up, mass=mt)
    hip = m.point("hip", (a1 + b1 + a2 + b2) * up, mass=mh, link="stance_foot")
    m.point("swing_thigh", hip - b2 * R3(th, sw_c), mass=mt)
    knee = m.point("swing_knee", hip - (a2 + b2) * R3(th, sw_c), link="hip")
    m.point("swing_shank", knee - b1 * R3(sh, sw_c), mass=ms)
    m.point("swing_foot", knee - (a1 + b1) * R3(sh, sw_c), link="swing_knee")
    m.point("torso", hip + lT * R3(tor, tor_c), mass=mT, link="hip")
    m.gravity(g)
    dot = m.dot
    # Eq. 40's spring-dampers on the coronal angles (absolute angles, no reaction, as printed)
    m.force([0, -k_sc * st_c - kv_sc * dot(st_c), 0, 0, -k_sw * sw_c - kv_sw * dot(sw_c), 0,
             -k_tc * tor_c - kv_tc * dot(tor_c)])
    m.torque(kT * (theta_d - tor) - kv * dot(tor), tor - st)  # Eq. 34 as in humanoid-2d
    step_length = -m.points["swing_foot"][0]  # Eq. 35: positive while the swing foot is behind
    m.torque(sp.Piecewise((-kleg * step_length, step_length > 0), (0, True)), th)

    locked = m.constrained(f"{NAME}-locked", {sh: th})
    s = Walker(NAME, {"unlocked": m, "locked": locked}, hip="hip", slope=slope, mirror="y", doc=__doc__)
    s.transition("knee_lock", "unlocked", *joint_lock(sh - th), "locked")
    swap = {st: th, st_c: -sw_c, th: st, sh: st, sw_c: -st_c, tor: tor, tor_c: -tor_c}
    s.transition("heel_strike", "locked", *heel_strike(locked, "swing_foot", slope, swap), "unlocked", step=True)
    s.terminal("scuffed", "unlocked", heel_strike(m, "swing_foot", slope, {})[0], status="scuffed")
    s.terminal("hip_on_ground", ["unlocked", "locked"], lambda mode: Guard(height_above_slope(mode, "hip", slope)))
    st0, sh0, th0, tr0, dst0, dsh0, dth0, dtr0 = _GAIT_2D
    s.default_start["unlocked"] = s.fixed_point_guess = [st0, 0.0, th0, sh0, 0.0, tr0, 0.0,
                                                         dst0, 0.0, dth0, dsh0, 0.0, dtr0, 0.0]
    return s
