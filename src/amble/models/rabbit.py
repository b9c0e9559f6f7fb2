"""RABBIT: the five-link planar biped (Chevallereau et al. 2003) on level ground, under HZD.

Point feet, four actuated joints (hips, knees), hybrid zero dynamics (Westervelt et al. 2007).

Links: a torso and two legs of femur and tibia. Parameters as given after
Chevallereau et al. 2003 / Westervelt et al. 2007, Table 6.3: torso ``mT`` 20 kg, length 0.625 m,
centre of mass ``pT`` 0.2 m above the hip, inertia ``IT`` 2.22 kg·m²; femur ``mf`` 6.8 kg,
``lf`` 0.4 m, centre of mass ``pf`` 0.163 m from the hip, ``If`` 1.08 kg·m²; tibia ``mt``
3.2 kg, ``lt`` 0.4 m, centre of mass ``pt`` 0.128 m from the knee, ``It`` 0.93 kg·m². Centre of
mass distances run from the proximal joint (hip for torso and femur, knee for tibia, as in the
cited table); inertias are about each link's centre of mass, as the table gives them (they
include the reflected rotor inertia of the motors).

Coordinates (rad): ``torso`` the torso's absolute angle from the vertical (positive leaning
forward, +x); the hip angles ``stance_hip``, ``swing_hip`` — each femur's absolute angle less the
torso's; the knee angles ``stance_knee``, ``swing_knee`` — each tibia's absolute angle less its
femur's. A link's absolute angle is that of the vector from its lower to its upper end
(``R(θ) = (sin θ, cos θ)``), so a positive knee angle bends the knee forward, as a human's. The
four inputs act on the four joint coordinates (``B`` = the last four unit columns), limits
150 N·m.

Control: virtual constraints on the four joint angles as Bézier polynomials of degree 5 in the
phase ``θ = torso + stance_hip + stance_knee/2`` (≈ the stance leg's angle), from
``θ⁺ = −0.25`` to ``θ⁻ = 0.25`` rad; the first two coefficients of every output make the zero
dynamics hybrid invariant (:func:`amble.analysis.hzd.invariant_parameters`, applied to the
defaults). The interior coefficients were fitted on the zero dynamics for a speed near
0.65 m/s, joint torques below 111 N·m, the swing foot clear of the ground and a margin of
speed over the step. The gait: step length 0.395 m with a forward-leaning torso (0.1 rad at the
footfall), step time 0.590 s, 0.67 m/s, restricted multiplier 0.769; its period-1 orbit lies on
the zero dynamics and is stable. ``epsilon`` 0.1 s, ``kp`` 1, ``kd`` 2.
"""

from amble import POSITIVE, Model, R, walker

NAME = "rabbit"
POSITION = 46  # after compass-gait-level

#: Bézier coefficients (rad), rows: stance hip, swing hip, stance knee, swing knee. The last
#: column is the pose at the footfall (step length 0.395 m); the interior ones were fitted for a
#: stable gait with the swing foot clear of the ground; the first two columns are the hybrid-
#: invariant ones for the rest (:func:`amble.analysis.hzd.invariant_parameters`).
ALPHA = [[-0.4, -0.3081551494564341, -0.16605346826621353, 0.2270601478435086, 0.04970721613181213, 0.1],
         [0.1, 0.11737909407493607, 0.00038439800609303394, -0.22976576788170783, -0.6299212649578043, -0.4],
         [0.1, -0.01896672967530122, 0.1612502508393034, 0.49611220938858624, 0.09494393675106377, 0.1],
         [0.1, 0.12216095445951894, 2.275019608209081, 0.39921662714633, 0.14579490709209958, 0.1]]


#: the gait's post-impact state on the zero dynamics (the fixed point; also the default start)
START = [0.1, -0.4, 0.1, 0.1, 0.1, 0.6105463, 0.82904739, 0.15687426, -1.07386594, 0.20003823]


def _model(alpha):
    m = Model("rabbit")
    T, hst, hsw, kst, ksw = m.coordinates("torso stance_hip swing_hip stance_knee swing_knee")
    mT, mf, mt, lf, lt, pT, pf, pt, IT, If, It, g, slope = m.parameters(
        mT=20.0, mf=6.8, mt=3.2, lf=0.4, lt=0.4, pT=0.2, pf=0.163, pt=0.128, IT=2.22, If=1.08, It=0.93,
        g=9.81, slope=0.0)
    m.restrict("mT mf mt lf lt pT pf pt IT If It g", POSITIVE)
    m.declare_units(mT="kg", mf="kg", mt="kg", lf="m", lt="m", pT="m", pf="m", pt="m", IT="kg*m^2",
                    If="kg*m^2", It="kg*m^2", g="m/s^2", slope="rad")
    f1, t1 = T + hst, T + hst + kst  # stance femur and tibia, absolute
    f2, t2 = T + hsw, T + hsw + ksw  # swing femur and tibia, absolute
    m.point("stance_foot", (0, 0))
    knee1 = m.point("stance_knee_joint", lt * R(t1), link="stance_foot")
    hip = m.point("hip", knee1 + lf * R(f1), link="stance_knee_joint")
    m.point("head", hip + 0.625 * R(T), link="hip")
    m.point("torso_com", hip + pT * R(T), mass=mT)
    m.point("stance_femur_com", hip - pf * R(f1), mass=mf)
    m.point("stance_tibia_com", knee1 - pt * R(t1), mass=mt)
    knee2 = m.point("swing_knee_joint", hip - lf * R(f2), link="hip")
    m.point("swing_femur_com", hip - pf * R(f2), mass=mf)
    m.point("swing_tibia_com", knee2 - pt * R(t2), mass=mt)
    m.point("swing_foot", knee2 - lt * R(t2), link="swing_knee_joint")
    for angle, inertia in ((T, IT), (f1, If), (t1, It), (f2, If), (t2, It)):
        m.inertia(angle, inertia)
    m.gravity(g)
    for name, q in (("u_stance_hip", hst), ("u_swing_hip", hsw), ("u_stance_knee", kst), ("u_swing_knee", ksw)):
        m.actuator(name, on=q, limit=150.0)
    m.virtual_constraints([hst, hsw, kst, ksw], T + hst + kst / 2, alpha, (-0.25, 0.25), epsilon=0.1)
    relabel = {T: T, hst: hsw, hsw: hst, kst: ksw, ksw: kst}
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel=relabel, doc=__doc__, start=START)


def build():
    return _model(ALPHA)
