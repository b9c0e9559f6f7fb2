"""Kuo's 3D passive walker: straight legs on a pelvis of width 2w, rolling sideways (Kuo 1999).

After A. D. Kuo, "Stabilization of lateral motion in passive dynamic walking", Int. J. Robotics
Research 18(9), 1999: a walker with legs at both ends of a pelvis has three degrees of freedom —
stance leg and swing leg in the sagittal plane and a roll of the whole body about the stance
foot — and a fixed splay of the legs. It walks down a slope passively, stable fore–aft but with
exactly one unstable lateral mode, which Kuo stabilises by placing the swing foot sideways once per
step, with linear feedback of the state. Here his three degrees of freedom are kept and the hips
get the abduction joints that a sideways foot placement needs::

            stance hip -- pelvis (M) -- swing hip      roll: pelvis about the downhill x axis,
                |          (w each side)     |           through the stance foot (> 0 lifts the swing hip)
      stance    |  m at c below the hip      | swing     stance, swing: leg angles about the pelvis axis,
                |                            |           foot → hip, > 0 leaning downhill (+x)
           stance foot                  swing foot     abd_stance, abd_swing: hip abduction, foot outward > 0

Each leg's direction (foot → hip) is ``Rx(roll)·R3(angle, ±abduction)``: a hip with a pitch axis
along the pelvis and an abduction axis. The swing hip is a stiff spring-damper (``k_hip``,
``c_hip``) towards the abduction ``splay + place``; the stance hip is a stiff damper
(``c_stance``): it keeps the abduction the leg landed with, as the fixed splay of Kuo's model does
(under load it drifts by 8 mrad over a step). So the walker has Kuo's three degrees of
freedom plus two fast hip modes, and with both hips rigid it is his model. Point feet (Kuo's walker
has curved feet), point masses (pelvis ``M``, each leg ``m`` at ``c`` below its hip). Heel strike
is amble's full 3D plastic impact, then the legs swap and ``y → −y`` (``mirror="y"``: roll changes
sign, the abductions swap). The model does not let the pelvis turn about the vertical (Kuo's has no
yaw either): the angular momentum about the impact point is conserved along the roll axis and
along the pelvis axis; about the third axis the feet take a torque impulse.

Parameters (chosen; Kuo's numbers are not reproduced): ``M`` 10 kg, ``m`` 5 kg, ``l`` 1 m,
``c`` 0.5 m (the thesis' compass-gait legs, as in compass-gait), ``w`` 0.1 m, ``splay`` 0 rad,
``place`` 0 rad (the foot placement of this step, set by the controller), ``k_hip`` 5000 N·m/rad,
``c_hip`` 120 N·m·s/rad, ``c_stance`` 2000 N·m·s/rad, ``g`` 9.81 m/s², ``slope`` 0.05 rad.

Passive gait at the defaults (the default start, post-impact): step 0.7294 s, multipliers
|μ| = 9.66 (real, the sideways fall: one unstable lateral mode, as Kuo reports), 0.560 (the
fore–aft pair), 0.146, 0.110, 0.004, 0, … With both hips rigid the same gait has |μ| = 9.58, 0.541,
0.145, 0.125. The abduction rates right after heel strike (±4.6 rad/s) are the fast hip transient
of a joint that is compliant during the impact; it decays within a few hundredths of a second.

Foot placement (Kuo's controller, once per step): ``place_k = gain · GAINS · (x_k − FIXED_POINT)``,
``x_k`` the post-impact state, ``GAINS`` the discrete LQR gain of the linearised step-to-step map
(Q = I, R = 1). :func:`walk_with_foot_placement` walks with it; ``gain=0`` is the passive walker.
With ``gain=1`` every multiplier of the closed loop is inside the unit circle (0.430 at most): a
sideways push of 1e-4 rad/s on the roll rate fells the passive walker within four steps, and with
foot placement the walker returns to its gait (deviation below 1e-7 after 16 steps). The region it
recovers from is small — a push of 1e-3 rad/s already fells it: the gain is large, the
step-to-step map strongly non-normal (deviations grow tenfold before they decay).
"""

from collections.abc import Mapping, Sequence

import numpy as np
import sympy as sp

from amble import NONNEGATIVE, POSITIVE, R3, Model, Walker, simulate, walker

NAME = "kuo-3d"
POSITION = 47  # place in `amble models` (ascending)

#: the passive gait (post-impact; stance swing roll abd_stance abd_swing, then rates)
FIXED_POINT = [-0.20260380009022877, 0.2889785663473741, 0.017148724772315705, -0.0001317236433473215,
               -0.007861874062785722, 1.2570638660309006, 1.3624857366186824, -4.365804021796373,
               -4.654084028179501, 4.556177249733533]
#: discrete LQR gain of the foot placement (rad per unit of state deviation), Q = I, R = 1
GAINS = [-1.233280873375514, 0.6615719642947181, -13.293683602813207, 16.386732006726, 1.5473512566941476,
         -1.4071132734211893, 0.09226529968204239, -3.83170306932545, 4.156727690606231, 0.38706595290899004]


def _rot_x(a):
    return sp.Matrix([[1, 0, 0], [0, sp.cos(a), -sp.sin(a)], [0, sp.sin(a), sp.cos(a)]])


def kuo_model(name: str = NAME) -> Model:
    """The walker's model in mode "walk" (coordinates ``stance swing roll abd_stance abd_swing``)."""
    m = Model(name, dims=3)
    st, sw, roll, a_st, a_sw = m.coordinates("stance swing roll abd_stance abd_swing")
    M, ml, l, c, w, g, slope = m.parameters(M=10.0, m=5.0, l=1.0, c=0.5, w=0.1, g=9.81, slope=0.05)
    splay, place, k_h, c_h, c_st = m.parameters(splay=0.0, place=0.0, k_hip=5000.0, c_hip=120.0, c_stance=2000.0)
    m.restrict("M m l c w g", POSITIVE)
    m.restrict("k_hip c_hip c_stance", NONNEGATIVE)
    body = _rot_x(roll)
    d_st, d_sw = body * R3(st, a_st), body * R3(sw, -a_sw)  # foot → hip directions
    m.point("stance_foot", (0, 0, 0))
    hip_st = m.point("stance_hip", l * d_st, link="stance_foot")
    m.point("stance_leg", hip_st - c * d_st, mass=ml)
    m.point("pelvis", hip_st + w * body[:, 1], mass=M, link="stance_hip")
    hip_sw = m.point("swing_hip", hip_st + 2 * w * body[:, 1], link="pelvis")
    m.point("swing_leg", hip_sw - c * d_sw, mass=ml)
    m.point("swing_foot", hip_sw - l * d_sw, link="swing_hip")
    m.gravity(g)
    m.add_potential(k_h / 2 * (a_sw - splay - place) ** 2)  # the swing hip's servo spring
    m.torque(-c_h * m.dot(a_sw), a_sw)
    m.torque(-c_st * m.dot(a_st), a_st)  # the stance hip holds the abduction the leg landed with
    return m


def build() -> Walker:
    m = kuo_model()
    st, sw, roll, a_st, a_sw = m.q
    relabel = {st: sw, sw: st, roll: -roll, a_st: a_sw, a_sw: a_st}
    return walker(m, foot="swing_foot", hip="pelvis", slope=m.symbol("slope"), relabel=relabel, mirror="y",
                  start=FIXED_POINT, doc=__doc__)


def rigid_walker() -> Walker:
    """Kuo's three degrees of freedom: both hips rigid at ``splay`` (coordinates ``stance swing roll``);
    its default start is its passive gait (step 0.7307 s)."""
    m = kuo_model()
    st, sw, roll, a_st, a_sw = m.q
    splay = m.symbol("splay")
    rigid = m.constrained(NAME + "-rigid", {a_st: splay, a_sw: splay})
    guess = [-0.20290571403702, 0.29150632448083, 0.01397533137335, 1.01215203174559, 0.39520911183276,
             0.30200832566792]
    return walker(rigid, foot="swing_foot", hip="pelvis", slope=m.symbol("slope"),
                  relabel={st: sw, sw: st, roll: -roll}, mirror="y", start=guess, doc="Kuo's walker, rigid hips")


def foot_placement(x: Sequence[float], gain: float = 1.0) -> float:
    """Kuo's once-per-step lateral foot placement (rad of swing-hip abduction) for the post-impact state ``x``."""
    return float(gain * np.dot(GAINS, np.asarray(x, float) - FIXED_POINT))


def walk_with_foot_placement(system: Walker, x0: Sequence[float], steps: int, gain: float = 1.0,
                             params: Mapping[str, float] | None = None) -> tuple[str, list[np.ndarray]]:
    """Walk ``steps`` steps from the post-impact state ``x0``, choosing ``place`` at every footfall
    with :func:`foot_placement`: the run's status and the post-impact states, ``x0`` first."""
    states = [np.asarray(x0, float)]
    for _ in range(steps):
        values = {**(params or {}), "place": foot_placement(states[-1], gain)}
        tr = simulate(system, states[-1], params=values, steps=1, samples=False)
        if tr.status != "completed":
            return tr.status, states
        states.append(np.asarray(tr.final_post_impact_state, float))
    return "completed", states
