"""Humanoid in 3D on level ground under controlled symmetry (ankle, hip and waist inputs).

The thesis' stated next step: its humanoid "is only able to move forward on a slope".

The robot, its coordinates, parameters and the thesis' generalized forces (torso PD, step-length
hip torque, spring-dampers) are those of ``humanoid-3d-yaw`` (thesis Section 4.4 without the
knee, with a pelvis and its yaw; see that model),
with the ground level (``slope`` 0). Every direction of the model is ``R3(Θ, Φ) = Ry(Θ)·(0, sin Φ,
cos Φ)`` and the upper-body frame is ``Ry(torso)·…``, so adding ``γ`` to the three sagittal
angles (``stance``, ``swing``, ``torso``) turns the whole robot by ``Ry(γ)`` about the lateral
axis: the kinetic energy and the 3D impact are unchanged, gravity turns. Seven inputs, one per
coordinate (generalized forces; ``B`` = identity: ankle pitch and roll of the stance foot, hip
pitch and roll of the swing leg, waist pitch, roll and yaw), apply Spong & Bullo's potential
shaping

    u = ∂V/∂q (q) − ∂V/∂q (q + γ·e_sagittal),        γ = ``emulated_slope`` 0.05 rad,

and the torso PD holds the torso at ``torso_d`` from the *emulated* vertical (``torso + γ``); the
step-length torque measures along the model's own ground. The closed loop on level ground is
then the slope walker turned by ``γ``: its gait is the ``humanoid-3d-yaw`` gait of slope ``γ`` with
the sagittal angles less ``γ``, the same velocities, step time and multipliers (the start below).
It needs ankle torques: a point foot cannot apply them; a real foot must keep the centre of
pressure inside it (not modelled).
"""

import sympy as sp

from amble import NONNEGATIVE, POSITIVE, R3, Model, Rx, Ry, Rz, Walker, distance_along_slope, walker

NAME = "humanoid-3d-level"
POSITION = 46  # after humanoid-3d-yaw


def upper_body_frame(torso, torso_cor, yaw):
    """Orientation (body → world) of the upper body (pelvis + torso): columns its x, y, z axes."""
    return Ry(torso) * Rx(-torso_cor) * Rz(yaw)


def build() -> Walker:
    m = Model(NAME, dims=3)
    st, sw, st_c, sw_c, tor, tor_c, yaw = m.coordinates("stance swing stance_cor swing_cor torso torso_cor yaw")
    mh, ml, mt, a, b, lt, w, g, slope, i_xy, i_z = m.parameters(
        mh=10.0, m=5.0, mt=3.0, a=0.53, b=0.47, lt=0.5, w=0.1, g=9.81, slope=0.0, I_xy=0.2, I_z=0.2)
    gamma = m.parameter("emulated_slope", 0.05, "slope whose gait the controller reproduces", "rad")
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
    step = -distance_along_slope(m, "swing_foot", slope)  # Eq. 35: > 0 while the swing foot is behind
    tau_leg = sp.Piecewise((-k_leg * step, step > 0), (0, True))
    dot = m.dot
    m.force([0, tau_leg, -k_sc * st_c - kv_sc * dot(st_c), -k_sw * sw_c - kv_sw * dot(sw_c),
             k_t * (th_d - (tor + gamma)) - kv_t * dot(tor), -k_tc * tor_c - kv_tc * dot(tor_c),
             -k_y * yaw - kv_y * dot(yaw)])
    # controlled symmetry: inputs on every coordinate (ankle pitch and roll of the stance foot,
    # hip pitch and roll of the swing leg, waist pitch, roll and yaw) replace the potential by
    # the one of the robot turned by γ about the lateral axis
    V = m.V
    turned = {st: st + gamma, sw: sw + gamma, tor: tor + gamma}
    names = ("ankle_pitch", "hip_pitch", "ankle_roll", "hip_roll", "waist_pitch", "waist_roll", "waist_yaw")
    laws = {}
    for name, q in zip(names, m.q):
        dv = sp.diff(V, q)
        laws[m.actuator(name, on=q)] = dv - dv.xreplace(turned)
    m.control(laws)
    relabel = {st: sw, sw: st, st_c: -sw_c, sw_c: -st_c, tor: tor, tor_c: -tor_c, yaw: -yaw}
    # the humanoid-3d fixed point at slope 0.05 (post-impact; step 0.7597 s), turned by γ = 0.05
    x_slope = [
        -0.17513872545372786, 0.21584692131603855, -0.0027109889560943323, -0.0007943995955461281,
        -0.026276535422660098, -0.11538290987512972, -0.005241697963894061, 0.824737150927434,
        0.6092596999815059, -0.08939453002223806, -0.12489102822875123, 0.1031354286921594,
        0.4242854569830537, -0.35175036643091706]
    x_star = [v - (0.05 if i in (0, 1, 4) else 0.0) for i, v in enumerate(x_slope)]
    return walker(m, foot="swing_foot", hip="hip", slope=slope, relabel=relabel, start=x_star, mirror="y",
                  doc=__doc__)
