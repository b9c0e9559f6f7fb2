"""The planar five-link biped as MuJoCo sees it: its MJCF (planar root, soft foot contact, one
motor per joint) and the map between amble's state and MuJoCo's ``(qpos, qvel)``.

The layout exported is RABBIT's (:mod:`amble.models.rabbit`): a torso and two legs of femur and
tibia with point feet, coordinates ``torso stance_hip swing_hip stance_knee swing_knee`` and
parameters ``mT mf mt lf lt pT pf pt IT If It g`` (their values, defaults or ``params``, set the
MJCF's masses, centres of mass and inertias). A robot file (URDF or MJCF) needs no export: MuJoCo
loads it directly.

Conventions, as amble's MJCF import (:mod:`amble.modelling.mjcf`) reads a file: x forward, z up,
y lateral; a hinge about +y by ``φ`` turns the z axis to ``(sin φ, 0, cos φ)``, which is amble's
``R(φ)``, so an absolute link angle of the model is the link's pitch in MuJoCo and a joint angle
(a difference of absolute angles) is MuJoCo's hinge angle of the child body. The MuJoCo legs are
``a`` and ``b``; the stance leg is ``a`` at the start and the legs swap roles at every footfall,
as amble's relabelling swaps the coordinates. Each link's inertia is its scalar planar inertia
about the ``y`` axis through its centre of mass (``diaginertia`` ``I I I``; the other two
components do not act in the plane).

Apart from :mod:`amble.analysis.mujoco_replay`, which runs the law in MuJoCo's loop: the export
and the change of coordinates are what MuJoCo needs to hold the robot at all, whatever runs it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from ..errors import ModelError, ParameterError
from ..modelling.walker import Walker
from .defaults import MUJOCO_CONTACT_TIME as CONTACT_TIME
from .defaults import MUJOCO_TIMESTEP as TIMESTEP

__all__ = ["COORDINATES", "MUJOCO_JOINTS", "amble_state", "mujoco_state", "planar_biped_mjcf"]

#: amble's coordinates of the exported layout, in order, and the MuJoCo joint each one is while leg
#: ``a`` stands (leg ``b`` standing swaps ``a`` and ``b``)
COORDINATES = ("torso", "stance_hip", "swing_hip", "stance_knee", "swing_knee")
_JOINT_OF = {"torso": "torso", "stance_hip": "hip_{s}", "swing_hip": "hip_{w}", "stance_knee": "knee_{s}",
             "swing_knee": "knee_{w}"}
#: MuJoCo's generalized coordinates of the export, in order
MUJOCO_JOINTS = ("rootx", "rootz", "torso", "hip_a", "knee_a", "hip_b", "knee_b")
_PARAMETERS = ("mT", "mf", "mt", "lf", "lt", "pT", "pf", "pt", "IT", "If", "It", "g")
#: the torso's drawn length (m; RABBIT's head point)
_TORSO_LENGTH = 0.625


def _ground_slope(system: Any, values: Mapping[str, float]) -> float:
    """The walker's ground slope (rad) at ``values``; 0 for a system that is no walker."""
    declared = system.symbolic()
    return declared.slope_value(values) if isinstance(declared, Walker) else 0.0


def _values(system: Any, params: Mapping[str, float] | None) -> dict[str, float]:
    """The system's parameter values with ``params`` applied; refuses a model of another layout."""
    declared = dict(system.parameters)
    mode = system.mode_names[0]
    names = system.state_names(mode)
    missing = [p for p in _PARAMETERS if p not in declared]
    if tuple(names[: len(COORDINATES)]) != COORDINATES or len(names) != 2 * len(COORDINATES) or missing:
        raise ModelError(f"model {system.name!r}: the MuJoCo export knows the planar five-link biped with "
                         f"coordinates {' '.join(COORDINATES)} and parameters {' '.join(_PARAMETERS)} "
                         "(RABBIT's layout); a robot file loads in MuJoCo directly")
    unknown = sorted(set(params or {}) - set(declared))
    if unknown:
        raise ParameterError(f"unknown parameter {unknown[0]!r} of model {system.name!r}")
    declared.update({k: float(v) for k, v in (params or {}).items()})
    if _ground_slope(system, declared) != 0.0:
        raise ParameterError("the MuJoCo export stands the robot on level ground: the walker's slope must be 0")
    return declared


def planar_biped_mjcf(system: Any, params: Mapping[str, float] | None = None, *, foot_radius: float = 0.005,
                      friction: float = 1.0, timestep: float = TIMESTEP, contact_time: float = CONTACT_TIME,
                      limits: Mapping[str, float | None] | None = None) -> str:
    """The MJCF text of a planar five-link biped (RABBIT's layout) with a ground plane.

    ``foot_radius`` (m): each point foot is a sphere of this radius centred on the foot, the floor
    lies ``foot_radius`` below ``z = 0`` so that a foot touches it at amble's height 0;
    ``friction``: the sliding friction coefficient of foot and floor; ``timestep`` (s): MuJoCo's
    step; ``contact_time`` (s): the time constant of the contact's spring-damper (MuJoCo's
    ``solref = "contact_time 1"``, critically damped; at least two ``timestep``), smaller is
    stiffer and closer to amble's rigid ground; ``limits``: MuJoCo joint name → torque limit
    (N·m; ``ctrlrange``), None for no limit.
    Only the feet collide, only with the floor.
    """
    v = _values(system, params)
    if not (foot_radius > 0 and friction > 0 and timestep > 0 and contact_time >= 2 * timestep):
        raise ParameterError(f"foot_radius, friction and timestep must be positive and contact_time at least two "
                             f"timesteps, got {foot_radius}, {friction}, {timestep}, {contact_time}")

    def inertial(z: float, mass: float, inertia: float) -> str:
        return f'<inertial pos="0 0 {z!r}" mass="{mass!r}" diaginertia="{inertia!r} {inertia!r} {inertia!r}"/>'

    def leg(s: str) -> str:
        lf, lt = v["lf"], v["lt"]
        return f"""
      <body name="femur_{s}">
        <joint name="hip_{s}" type="hinge" axis="0 1 0"/>
        {inertial(-v["pf"], v["mf"], v["If"])}
        <geom type="capsule" fromto="0 0 0 0 0 {-lf!r}" size="0.02" contype="0" conaffinity="0" group="1"/>
        <body name="tibia_{s}" pos="0 0 {-lf!r}">
          <joint name="knee_{s}" type="hinge" axis="0 1 0"/>
          {inertial(-v["pt"], v["mt"], v["It"])}
          <geom type="capsule" fromto="0 0 0 0 0 {-lt!r}" size="0.015" contype="0" conaffinity="0" group="1"/>
          <geom name="foot_{s}" type="sphere" pos="0 0 {-lt!r}" size="{foot_radius!r}" contype="1"
                conaffinity="0" condim="3" friction="{friction!r} 0.005 0.0001" solref="{contact_time!r} 1"/>
          <site name="foot_{s}" pos="0 0 {-lt!r}"/>
        </body>
      </body>"""

    motors = []
    for joint in MUJOCO_JOINTS[3:]:
        lim = (limits or {}).get(joint)
        rng = f' ctrlrange="{-lim!r} {lim!r}" ctrllimited="true"' if lim is not None else ' ctrllimited="false"'
        motors.append(f'    <motor name="{joint}" joint="{joint}" gear="1"{rng}/>')
    return f"""<mujoco model={quoteattr(system.name)}>
  <compiler angle="radian" inertiafromgeom="false"/>
  <option timestep="{timestep!r}" gravity="0 0 {-v["g"]!r}" integrator="implicitfast"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" pos="0 0 {-foot_radius!r}" contype="0" conaffinity="1"
          friction="{friction!r} 0.005 0.0001" solref="{contact_time!r} 1"/>
    <body name="torso">
      <joint name="rootx" type="slide" axis="1 0 0"/>
      <joint name="rootz" type="slide" axis="0 0 1"/>
      <joint name="torso" type="hinge" axis="0 1 0"/>
      {inertial(v["pT"], v["mT"], v["IT"])}
      <geom type="capsule" fromto="0 0 0 0 0 {_TORSO_LENGTH!r}" size="0.03" contype="0" conaffinity="0"
            group="1"/>
      <site name="hip"/>{leg("a")}{leg("b")}
    </body>
  </worldbody>
  <actuator>
{chr(10).join(motors)}
  </actuator>
</mujoco>
"""


def _order(stance: int) -> list[int]:
    s, w = ("a", "b") if stance == 0 else ("b", "a")
    return [MUJOCO_JOINTS.index(_JOINT_OF[c].format(s=s, w=w)) for c in COORDINATES]


_ORDERS = (_order(0), _order(1))


def _joint_order(stance: int) -> list[int]:
    """Index into MuJoCo's ``qpos`` of each amble coordinate while leg ``stance`` (0: a, 1: b) stands."""
    return _ORDERS[stance]


def mujoco_state(x: Sequence[float], values: Mapping[str, float], stance: int = 0,
                 foot: Sequence[float] = (0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's ``(qpos, qvel)`` of amble's state ``x`` (``COORDINATES`` then their rates) with the
    stance foot of leg ``stance`` at ``foot = (x, z)`` (m) and not moving: the hip is where the
    stance leg puts it, ``hip = foot + lt R(θ_tibia) + lf R(θ_femur)``, and moves as it carries it."""
    x = np.asarray(x, dtype=float)
    q, qd = x[:5], x[5:]
    f1, t1 = q[0] + q[1], q[0] + q[1] + q[3]
    f1d, t1d = qd[0] + qd[1], qd[0] + qd[1] + qd[3]
    lf, lt = values["lf"], values["lt"]

    def r(a: float) -> np.ndarray:  # amble's R(θ) in the (x, z) plane, and its derivative
        return np.array([np.sin(a), np.cos(a)])

    def dr(a: float) -> np.ndarray:
        return np.array([np.cos(a), -np.sin(a)])

    hip = np.asarray(foot, dtype=float) + lt * r(t1) + lf * r(f1)
    hip_d = lt * t1d * dr(t1) + lf * f1d * dr(f1)
    qpos, qvel = np.zeros(len(MUJOCO_JOINTS)), np.zeros(len(MUJOCO_JOINTS))
    qpos[:2], qvel[:2] = hip, hip_d
    idx = _joint_order(stance)
    qpos[idx], qvel[idx] = q, qd
    return qpos, qvel


def amble_state(qpos: np.ndarray, qvel: np.ndarray, stance: int) -> np.ndarray:
    """amble's state (``COORDINATES`` then their rates) of MuJoCo's ``(qpos, qvel)`` with leg
    ``stance`` standing."""
    idx = _joint_order(stance)
    return np.concatenate([qpos[idx], qvel[idx]])
