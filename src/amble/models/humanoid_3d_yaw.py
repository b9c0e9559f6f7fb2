"""Humanoid in 3D with pelvis yaw (thesis 4.4 without the knee): straight legs, a pelvis of width ``w``, a torso.

Coordinates (absolute angles; every leg/torso direction is ``R3(Θ, Φ)``, Eq. 37)::

          torso (m_T)          stance, stance_cor: Θ, Φ of the stance leg, foot → hip
            |  l_T             swing,  swing_cor:  Θ, Φ of the swing leg,  foot → hip
    R-hip --hip(m_H)-- L-hip   torso,  torso_cor:  Θ, Φ of the torso, hip → torso mass
      |    (w/2)  (w/2)  |     yaw: turn of the upper body (pelvis + torso) about the torso axis;
    stance               swing      upper-body frame Ry(torso)·Rx(−torso_cor)·Rz(yaw): its z column is
     (m at b from foot)             the torso axis R3(torso, torso_cor), its y column the pelvis axis

Θ (sagittal) > 0 leans downhill (+x), Φ (coronal) > 0 leans to +y (left). Template: the stance
leg is the right leg (pelvis runs +y from stance hip to swing hip). Heel strike is amble's full 3D
plastic impact of the swing foot (all three angular-momentum components about it are conserved),
then the legs swap and y → −y (``mirror="y"``): Θ's swap, Φ's swap with a sign flip, torso_cor and
yaw change sign, so the return map is period-1 in mirrored coordinates. The pelvis needs its third
orientation angle ``yaw`` (instead of the thesis' swing knee, dropped here): without it a
whole-body rotation about the impact point is not a motion of the model and the 3D impact could
not conserve angular momentum. The upper body is the point masses m_H, m_T (Eq. 38–39) plus a
rigid-body inertia diag(I_xy, I_xy, I_z) in its own frame (about the torso mass), which gives the
pelvis the yaw inertia a point-mass chain lacks.

Controls Γ on the coordinates (thesis Eq. 40: generalized forces without reaction), as listed:
stance: 0; swing: −k_leg·L while the step length L > 0 (swing foot behind, Eq. 35); stance_cor:
−k_sc Φ₁ − kv_sc Φ̇₁ (a stance-ankle roll spring-damper; Eq. 40 has 0 here, but it is what makes the
cycle stable: below k_sc ≈ 80 N·m/rad a real multiplier of the sideways-roll mode passes 1, e.g.
1.76 at k_sc = 20); torso: k_t(θ_d − Θ_T) − kv_t Θ̇_T (Eq. 34); swing_cor, torso_cor, yaw:
−k θ − k_v θ̇ (the spring-dampers τ_i = k_i θ_i + k_vi θ̇_i of Eq. 40, signs chosen to restore).

Parameters: ``mh`` 10 kg, ``m`` 5 kg, ``a`` 0.53 m, ``b`` 0.47 m (leg length 1 m; Table 3, locked
leg), ``mt`` 3 kg and ``lt`` 0.5 m (Table 4; its "5" read as 0.5 m), ``w`` 0.1 m, ``I_xy`` 0.2 and
``I_z`` 0.2 kg·m² (chosen: a 13 kg upper body of radius ≈ 0.15 m), ``g`` 9.81 m/s², ``slope``
0.05 rad. Gains (chosen; N·m/rad, N·m·s/rad, N·m/m): k_leg 5 (as humanoid-2d), k_sc 400, kv_sc
40, k_sw 50, kv_sw 20, k_t 60, kv_t 20, torso_d 0, k_tc 100, kv_tc 20, k_yaw 50, kv_yaw 10.
``I_z`` leaves the multipliers essentially unchanged but sets the yaw rate after impact (−0.35 rad/s here,
−16 rad/s with ``I_z`` 0: the point masses alone give the pelvis almost no yaw inertia).

State: ``stance swing stance_cor swing_cor torso torso_cor yaw`` then their ``_dot`` (rad, rad/s).
Default start = fixed-point guess = the stable period-1 fixed point (post-impact):
x* = (−0.17514, 0.21585, −0.00271, −0.00079, −0.02628, −0.11538, −0.00524, 0.82474, 0.60926,
−0.08939, −0.12489, 0.10314, 0.42429, −0.35175); step time 0.7597 s, step 0.388 m downhill, feet
alternating at y = 0 and 0.097 m (a straight walk). Floquet multipliers |λ| = 0.530 (complex
pair; its eigenvector lies mostly in torso, torso_cor, yaw and stance rates), 0.302 (pair), 0.165,
0.101 (pair), 0.012, … — all inside the unit circle. The cycle attracts: walking from the
humanoid-2d gait with the coronal angles and yaw at zero converges to x*.
"""

import sympy as sp

from amble import NONNEGATIVE, POSITIVE, R3, Model, Rx, Ry, Rz, Walker, distance_along_slope, walker

NAME = "humanoid-3d-yaw"
POSITION = 45  # place in `amble models` (ascending)


def upper_body_frame(torso, torso_cor, yaw):
    """Orientation (body → world) of the upper body (pelvis + torso): columns its x, y, z axes."""
    return Ry(torso) * Rx(-torso_cor) * Rz(yaw)


#: The stable period-1 fixed point at slope 0.05 (post-impact; step 0.7597 s, |multipliers| ≤ 0.531).
FIXED_POINT = [
    -0.17513872545372786, 0.21584692131603855, -0.0027109889560943323, -0.0007943995955461281,
    -0.026276535422660098, -0.11538290987512972, -0.005241697963894061, 0.824737150927434,
    0.6092596999815059, -0.08939453002223806, -0.12489102822875123, 0.1031354286921594,
    0.4242854569830537, -0.35175036643091706]


def model(name: str = NAME, slope: float = 0.05, emulated_slope: float | None = None) -> Model:
    """The robot with its passive and PD forces, before its walker is declared. With
    ``emulated_slope`` it gains that parameter (rad), and the torso PD holds the torso upright
    from the vertical of that emulated slope (a controller that turns the robot adds the rest)."""
    m = Model(name, dims=3)
    st, sw, st_c, sw_c, tor, tor_c, yaw = m.coordinates("stance swing stance_cor swing_cor torso torso_cor yaw")
    mh, ml, mt, a, b, lt, w, g, slope_, i_xy, i_z = m.parameters(
        mh=10.0, m=5.0, mt=3.0, a=0.53, b=0.47, lt=0.5, w=0.1, g=9.81, slope=slope, I_xy=0.2, I_z=0.2)
    upright = 0 if emulated_slope is None else m.parameter(
        "emulated_slope", emulated_slope, "slope whose gait the controller reproduces", "rad")
    k_leg, k_sc, kv_sc, k_sw, kv_sw = m.parameters(k_leg=5.0, k_sc=400.0, kv_sc=40.0, k_sw=50.0, kv_sw=20.0)
    k_t, kv_t, th_d, k_tc, kv_tc, k_y, kv_y = m.parameters(
        k_t=60.0, kv_t=20.0, torso_d=0.0, k_tc=100.0, kv_tc=20.0, k_yaw=50.0, kv_yaw=10.0)
    m.restrict("mh m mt a b lt w g", POSITIVE)
    m.restrict("I_xy I_z k_leg k_sc kv_sc k_sw kv_sw k_t kv_t k_tc kv_tc k_yaw kv_yaw", NONNEGATIVE)
    frame = upper_body_frame(tor, tor_c, yaw)
    pelvis = frame[:, 1]
    m.point("stance_foot", (0, 0, 0))
    hip_r = m.point("stance_hip", (a + b) * R3(st, st_c), link="stance_foot")
    m.point("stance_mass", b * R3(st, st_c), mass=ml)
    hip = m.point("hip", hip_r + w / 2 * pelvis, mass=mh, link="stance_hip")
    hip_l = m.point("swing_hip", hip_r + w * pelvis, link="hip")
    m.point("swing_mass", hip_l - a * R3(sw, sw_c), mass=ml)
    m.point("swing_foot", hip_l - (a + b) * R3(sw, sw_c), link="swing_hip")
    m.point("torso", hip + lt * R3(tor, tor_c), mass=mt, link="hip")
    m.body_inertia(frame, sp.diag(i_xy, i_xy, i_z))
    m.gravity(g)
    step = -distance_along_slope(m, "swing_foot", slope_)  # Eq. 35: > 0 while the swing foot is behind
    tau_leg = sp.Piecewise((-k_leg * step, step > 0), (0, True))
    dot = m.dot
    m.force([0, tau_leg, -k_sc * st_c - kv_sc * dot(st_c), -k_sw * sw_c - kv_sw * dot(sw_c),
             k_t * (th_d - (tor + upright)) - kv_t * dot(tor), -k_tc * tor_c - kv_tc * dot(tor_c),
             -k_y * yaw - kv_y * dot(yaw)])
    return m


def as_walker(m: Model, start: list[float], doc: str | None) -> Walker:
    """The walker of :func:`model`'s robot: heel strike of the swing foot, legs and lateral angles
    mirrored."""
    st, sw, st_c, sw_c, tor, tor_c, yaw = m.q
    relabel = {st: sw, sw: st, st_c: -sw_c, sw_c: -st_c, tor: tor, tor_c: -tor_c, yaw: -yaw}
    return walker(m, foot="swing_foot", hip="hip", slope=m.symbol("slope"), relabel=relabel, start=start,
                  mirror="y", doc=doc)


def build() -> Walker:
    return as_walker(model(), FIXED_POINT, __doc__)
