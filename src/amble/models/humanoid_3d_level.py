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

from amble import Walker
from amble.models import humanoid_3d_yaw

NAME = "humanoid-3d-level"
POSITION = 46  # after humanoid-3d-yaw


def build() -> Walker:
    m = humanoid_3d_yaw.model(NAME, slope=0.0, emulated_slope=0.05)
    st, sw, _, _, tor, _, _ = m.q
    gamma = m.symbol("emulated_slope")
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
    # the humanoid-3d-yaw fixed point at slope 0.05 (post-impact; step 0.7597 s), turned by γ = 0.05
    start = [v - (0.05 if i in (0, 1, 4) else 0.0) for i, v in enumerate(humanoid_3d_yaw.FIXED_POINT)]
    return humanoid_3d_yaw.as_walker(m, start, __doc__)
