"""Humanoid in 3D (thesis Section 4.4, 5.2, Eq. 37–40): two straight legs, a pelvis of width ``w``, a torso.

Coordinates (absolute angles; every leg/torso direction is ``R3(Θ, Φ)``, Eq. 37)::

          torso (m_T)          stance, stance_cor: Θ, Φ of the stance leg, foot → hip
            |  l_T             swing,  swing_cor:  Θ, Φ of the swing leg,  foot → hip
    R-hip --hip(m_H)-- L-hip   torso,  torso_cor:  Θ, Φ of the torso, hip → torso mass
      |    (w/2)  (w/2)  |     yaw: turn of the upper body (pelvis + torso) about the torso axis;
    stance               swing      the pelvis axis is column y of Ry(torso)·Rx(−torso_cor)·Rz(yaw)
     (m at b from foot)

Θ (sagittal) > 0 leans downhill (+x), Φ (coronal) > 0 leans to +y (left). Template: the stance
leg is the right leg (pelvis runs +y from stance hip to swing hip). Heel strike swaps the legs
and mirrors y → −y, so the post-impact state is again in the template: Θ's swap, Φ's swap with a
sign flip, torso_cor and yaw change sign (a period-1 return map in mirrored coordinates). The
pelvis needs its third orientation angle ``yaw`` (instead of the thesis' swing knee, dropped
here): without it a whole-body rotation about the impact point is not a motion of the model and
the 3D impact could not conserve all three components of angular momentum.

Controls Γ (generalized forces, thesis Eq. 40 style; signs chosen to stabilise):
swing: −k_leg·L while the swing foot is behind (L > 0, Eq. 35); stance_cor: −k_sc Φ₁ − kv_sc Φ̇₁
(an ankle-like roll damper, not in the thesis); swing_cor: −k_sw(Φ₂ − c_sw Φ₁) − kv_sw(…)˙ (lateral
foot placement: the swing leg mirrors the stance leg); torso: k_t(θ_d − Θ_T) − kv_t Θ̇_T (Eq. 34);
torso_cor: −k_tc Φ_T − kv_tc Φ̇_T; yaw: −k_yaw ψ − kv_yaw ψ̇.

Parameters: ``mh`` 10 kg, ``m`` 5 kg, ``a`` 0.53 m, ``b`` 0.47 m (leg length 1 m; Table 3, locked
leg), ``mt`` 3 kg and ``lt`` 0.5 m (Table 4; its "5" read as 0.5 m), ``w`` 0.1 m (chosen), ``g``
9.81, ``slope`` 0.05 rad (thesis). Gains (chosen): k_sw 50, kv_sw 20, c_sw −0.7, k_sc 20, kv_sc 45,
k_t 60, kv_t 20, torso_d 0, k_tc 100, kv_tc 20, k_yaw 50, kv_yaw 10, k_leg 0.

State: ``stance swing stance_cor swing_cor torso torso_cor yaw`` then their ``_dot`` (rad, rad/s).
Default start = default fixed-point guess = the period-1 fixed point (step time 0.730 s). With
these gains it has one multiplier of modulus 1.175 (the others ≤ 0.42): the cycle is not yet stable.
"""

import sympy as sp

from amble import R3, Model, distance_along_slope, walker

NAME = "humanoid-3d"


def _rot_y(a):
    return sp.Matrix([[sp.cos(a), 0, sp.sin(a)], [0, 1, 0], [-sp.sin(a), 0, sp.cos(a)]])


def _rot_x(a):
    return sp.Matrix([[1, 0, 0], [0, sp.cos(a), -sp.sin(a)], [0, sp.sin(a), sp.cos(a)]])


def _rot_z(a):
    return sp.Matrix([[sp.cos(a), -sp.sin(a), 0], [sp.sin(a), sp.cos(a), 0], [0, 0, 1]])


def build():
    m = Model("humanoid-3d", dims=3)
    st, sw, st_c, sw_c, tor, tor_c, yaw = m.coordinates("stance swing stance_cor swing_cor torso torso_cor yaw")
    mh, ml, mt, a, b, lt, w, g, slope = m.parameters(
        mh=10.0, m=5.0, mt=3.0, a=0.53, b=0.47, lt=0.5, w=0.1, g=9.81, slope=0.05)
    k_sw, kv_sw, k_t, kv_t, th_d, k_tc, kv_tc, k_y, kv_y, k_leg = m.parameters(
        k_sw=50.0, kv_sw=20.0, k_t=60.0, kv_t=20.0, torso_d=0.0, k_tc=100.0, kv_tc=20.0, k_yaw=50.0, kv_yaw=10.0,
        k_leg=0.0)
    c_sw, k_sc, kv_sc = m.parameters(c_sw=-0.7, k_sc=20.0, kv_sc=45.0)
    frame = _rot_y(tor) * _rot_x(-tor_c) * _rot_z(yaw)   # upper body (pelvis + torso): columns x, y, z axes
    pelvis = frame[:, 1]
    m.point("stance_foot", (0, 0, 0))
    hip_r = m.point("stance_hip", (a + b) * R3(st, st_c), link="stance_foot")
    m.point("stance_mass", b * R3(st, st_c), mass=ml)
    hip = m.point("hip", hip_r + w / 2 * pelvis, mass=mh, link="stance_hip")
    hip_l = m.point("swing_hip", hip_r + w * pelvis, link="hip")
    m.point("swing_mass", hip_l - a * R3(sw, sw_c), mass=ml)
    m.point("swing_foot", hip_l - (a + b) * R3(sw, sw_c), link="swing_hip")
    m.point("torso", hip + lt * R3(tor, tor_c), mass=mt, link="hip")
    m.gravity(g)
    step = -distance_along_slope(m, "swing_foot", slope)
    tau_leg = sp.Piecewise((-k_leg * step, step > 0), (0, True))
    dot = m.dot
    abd = sw_c - c_sw * st_c  # lateral foot placement: the swing leg's roll relative to the mirrored stance leg
    m.force([0, tau_leg, -k_sc * st_c - kv_sc * dot(st_c), -k_sw * abd - kv_sw * m.dt(abd),
             k_t * (th_d - tor) - kv_t * dot(tor), -k_tc * tor_c - kv_tc * dot(tor_c), -k_y * yaw - kv_y * dot(yaw)])
    relabel = {st: sw, sw: st, st_c: -sw_c, sw_c: -st_c, tor: tor, tor_c: -tor_c, yaw: -yaw}
    start = [-0.15208749360103987, 0.1747781053230539, -0.01663107387797514, 0.03812011553128779,
             -0.02023373588125623, -0.11997518307577128, -0.007310061023068697, 0.4961511109869042,
             1.1682743467175396, 0.020196235729229562, -0.030027641265722483, -0.05024491725091287,
             0.37413974327153915, -5.405675515006873]
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel=relabel, start=start, doc=__doc__)
