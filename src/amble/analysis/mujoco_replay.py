"""A planar biped and its controlled gait in MuJoCo: the robot as MJCF, soft ground contact, amble's
control law in MuJoCo's loop, and the drift between the two runs per step.

amble's walker is pinned at its stance foot and its footfall is an instantaneous plastic impact;
MuJoCo's robot is free in the sagittal plane (a *planar root*: ``rootx`` slides along x,
``rootz`` along z, the hinge ``torso`` turns about +y) and stands on the ground through a soft,
penetrable contact with friction. Replaying the same control law in both tells how much of a gait
survives soft contacts before it is tried on hardware.

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

The control law is amble's compiled one: at every MuJoCo step the state is read in amble's
coordinates (stance leg first) and the generalized force ``Γ + B u`` of the compiled model is
applied through one motor per actuated joint (``ctrl`` = ``u``, clipped to the declared limits).
A footfall in MuJoCo is the swing foot touching the ground ahead of the stance foot.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from ..errors import ModelError, ParameterError
from ..modelling.walker import Walker
from .defaults import MUJOCO_CONTACT_TIME as CONTACT_TIME
from .defaults import MUJOCO_TIMESTEP as TIMESTEP

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


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError as e:  # pragma: no cover - a declared dependency of the extra
        raise ModelError("the MuJoCo export needs the 'mujoco' package: pip install 'amble[mjcf]'") from e
    return mujoco


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


def _number(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


@dataclass
class StepDrift:
    """One step of both runs: MuJoCo's and amble's step time (s) and step length (m, foot to
    foot at the footfall), the RMS difference of the five angles over the step (rad, at equal
    time since the step began, over the shorter of the two steps), MuJoCo's stance foot: how
    far it slid along the ground (m) and how deep it sank at most (m), and — for a law of virtual
    constraints — the largest output error ``|y|`` over the step in MuJoCo (rad; amble's gait
    keeps ``y = 0``: it measures how far the soft footfall throws the robot off the zero
    dynamics), NaN without them."""

    step: int
    step_time: float
    amble_step_time: float
    step_length: float
    amble_step_length: float
    angle_rms: float
    stance_slip: float
    penetration: float
    max_output: float

    def to_json(self) -> dict[str, Any]:
        """The fields as JSON numbers (NaN, where amble's run has no such step, as null)."""
        return {k: (int(v) if k == "step" else _number(v)) for k, v in self.__dict__.items()}


@dataclass
class MujocoReplay:
    """The outcome of :func:`replay_in_mujoco`: ``status`` ``completed`` (all steps walked) or
    ``fell`` (hip below half its height at the start, the torso beyond horizontal, or no footfall
    in three amble step times),
    the steps walked, their drift from amble's run, the largest input the law asked for (N·m;
    MuJoCo clips it to the declared limits), how long any input was clipped in all (s; the law
    meets each soft footfall with the velocities before the impact, for a few ms), the time
    walked (s) and the MJCF."""

    status: str
    steps: int
    drift: list[StepDrift]
    max_input: float
    saturated_time: float
    time: float
    mjcf: str = field(repr=False)

    def summary(self) -> dict[str, float]:
        """The largest drift over the steps: ``|Δ step time|`` (s), ``|Δ step length|`` (m), angle
        RMS (rad), stance-foot slip and penetration (m), output error ``|y|`` (rad)."""

        def worst(values: Any) -> float:  # NaN where amble's run has no such step
            return max((v for v in values if np.isfinite(v)), default=float("nan"))

        d = self.drift
        if not d:
            return {}
        return {"max_step_time_error": worst(abs(s.step_time - s.amble_step_time) for s in d),
                "max_step_length_error": worst(abs(s.step_length - s.amble_step_length) for s in d),
                "max_angle_rms": worst(s.angle_rms for s in d),
                "max_stance_slip": worst(s.stance_slip for s in d),
                "max_output": worst(s.max_output for s in d),
                "max_penetration": worst(s.penetration for s in d)}

    def to_json(self) -> dict[str, Any]:
        return {"status": self.status, "steps": self.steps, "time": self.time, "max_input": self.max_input,
                "saturated_time": self.saturated_time, "drift": {k: _number(v) for k, v in self.summary().items()},
                "per_step": [s.to_json() for s in self.drift]}


class _Reference:
    """amble's own run from the same state: per step its start time, step time, step length
    (swing foot less stance foot at the footfall, m) and its sampled angles."""

    def __init__(self, system: Any, x0: np.ndarray, values: Mapping[str, float], steps: int, dt: float) -> None:
        from ..simulation.simulate import simulate

        tr = self.tr = simulate(system, x0, params=dict(values), steps=steps, sample_dt=dt)
        events = tr.step_events
        self.starts = np.array([0.0] + [e.t for e in events])
        self.times = np.diff(self.starts)
        names = tr.kernels.meta["points"]
        pre = np.array([e.x_pre for e in events]).reshape(len(events), len(x0))
        pos, _ = tr.kernels.kinematics_rows(self.starts[1:], np.zeros(len(events), dtype=np.int64), pre, tr.params)
        self.lengths = pos[:, names.index("swing_foot"), 0] - pos[:, names.index("stance_foot"), 0]

    def mean_step_time(self) -> float:
        return float(np.mean(self.times)) if len(self.times) else 1.0

    def step(self, k: int) -> tuple[float, float]:
        """Step ``k``'s time (s) and length (m); NaN after amble's run ended."""
        if k >= len(self.times):
            return float("nan"), float("nan")
        return float(self.times[k]), float(self.lengths[k])

    def angle_rms(self, k: int, t: np.ndarray, q: np.ndarray) -> float:
        """RMS difference (rad) of angles ``q`` sampled at ``t`` since step ``k`` began from amble's
        at the same times, over the shorter of the two steps."""
        if k >= len(self.times):
            return float("nan")
        tr, t0, t1 = self.tr, self.starts[k], self.starts[k + 1]
        # from the post-impact row at t0 to the pre-impact row at t1 (events give a row on both sides)
        i0 = int(np.searchsorted(tr.t, t0, side="right")) - 1
        i1 = int(np.searchsorted(tr.t, t1, side="left"))
        ta, qa = tr.t[i0 : i1 + 1] - t0, tr.x[i0 : i1 + 1, : len(COORDINATES)]
        keep = t <= min(ta[-1], t[-1])
        qi = np.column_stack([np.interp(t[keep], ta, qa[:, j]) for j in range(qa.shape[1])])
        return float(np.sqrt(np.mean((q[keep] - qi) ** 2)))


class _Walk:
    """MuJoCo's run, one step of MuJoCo at a time, with the footfall bookkeeping."""

    def __init__(self, system: Any, values: Mapping[str, float], xml: str, x0: np.ndarray) -> None:
        from ..backend.kernels import compiled
        from ..simulation.simulate import parameter_vector

        mj = self.mj = _mujoco()
        self.m = mj.MjModel.from_xml_string(xml)
        self.d = mj.MjData(self.m)
        self.k = compiled(system)
        self.p = parameter_vector(self.k, dict(values), system)
        self.mode = system.mode_names[0]
        self.stance = 0
        qpos, qvel = mujoco_state(x0, values, 0)
        self.d.qpos[:], self.d.qvel[:] = qpos, qvel
        mj.mj_forward(self.m, self.d)
        self.feet = [mj.mj_name2id(self.m, mj.mjtObj.mjOBJ_GEOM, f"foot_{s}") for s in "ab"]
        self.sites = [mj.mj_name2id(self.m, mj.mjtObj.mjOBJ_SITE, f"foot_{s}") for s in "ab"]
        self.hip = mj.mj_name2id(self.m, mj.mjtObj.mjOBJ_SITE, "hip")
        # the motor of each amble coordinate, per stance leg (the torso has none)
        model = system.symbolic().modes[self.mode]
        self.outputs = None
        if getattr(model, "virtual", None) is not None:
            import sympy as sp  # the outputs alone: y(q) needs no derivation

            self.outputs = sp.lambdify([*model.q, *model.params], list(model.virtual.y), "numpy", cse=True)
            self.output_params = [dict(values)[str(q)] for q in model.params]
        acts = [mj.mj_name2id(self.m, mj.mjtObj.mjOBJ_ACTUATOR, j) for j in MUJOCO_JOINTS[3:]]
        self.motor = [[acts[MUJOCO_JOINTS[3:].index(MUJOCO_JOINTS[i])] for i in _joint_order(s)[1:]] for s in (0, 1)]

    def state(self) -> np.ndarray:
        return amble_state(self.d.qpos, self.d.qvel, self.stance)

    def check(self, system: Any) -> None:
        """Refuse a model whose names are RABBIT's but whose mechanics are not the export's (or that
        forces the torso's angle, which has no motor): with the stance foot held, MuJoCo's ``M``
        and bias must be amble's at the start (1e-8).

        MuJoCo's velocities are ``J q̇`` with ``J`` from its foot Jacobian ``J_c`` (``J_c J = 0``,
        joints one to one), its accelerations ``J q̈ − J̇_c q̇`` on the root's slides."""
        mj, m, d = self.mj, self.m, self.d
        site = self.sites[self.stance]
        jp, jr, dp, dr = (np.zeros((3, m.nv)) for _ in range(4))
        mj.mj_jacSite(m, d, jp, jr, site)
        mj.mj_jacDot(m, d, dp, dr, d.site_xpos[site], int(m.site_bodyid[site]))
        rows = _joint_order(self.stance)
        J = np.zeros((m.nv, len(rows)))
        J[rows, range(len(rows))] = 1.0
        J[:2] = -jp[[0, 2]][:, rows]  # the root's slides move the foot as themselves
        a = np.zeros(m.nv)
        a[:2] = -(dp[[0, 2]] @ d.qvel)
        full = np.zeros((m.nv, m.nv))
        try:
            mj.mj_fullM(m, d, full)  # MuJoCo 4
        except TypeError:
            mj.mj_fullM(m, full, d.qM)  # MuJoCo 3
        M, h, gamma = self.k.dynamics(self.mode, 0.0, self.state(), self.p)
        if abs(gamma[0]) > 1e-9 * max(np.max(np.abs(gamma)), 1.0):
            raise ModelError(f"model {system.name!r}: a generalized force acts on the torso's angle, which the "
                             "export has no motor for")
        err = max(np.max(np.abs(J.T @ full @ J - M)) / np.max(np.abs(M)),
                  np.max(np.abs(J.T @ (full @ a + d.qfrc_bias) - h)) / max(np.max(np.abs(h)), 1.0))
        if not err < 1e-8:
            raise ModelError(f"model {system.name!r}: its mechanics are not the exported biped's (mass matrix "
                             f"or bias differ by {err:.2g} relative): the export knows RABBIT's layout only")

    def control(self, x: np.ndarray) -> np.ndarray:
        """amble's law at amble's state ``x``: ``Γ + B u`` on the joints (N·m)."""
        _, _, gamma = self.k.dynamics(self.mode, float(self.d.time), x, self.p)
        u = gamma[1:]
        self.d.ctrl[self.motor[self.stance]] = u
        return u

    def touchdown(self) -> bool:
        """The swing foot touches the floor ahead of the stance foot."""
        swing, xpos = self.feet[1 - self.stance], self.d.site_xpos
        if xpos[self.sites[1 - self.stance], 0] <= xpos[self.sites[self.stance], 0] or not self.d.ncon:
            return False
        return bool(np.any(self.d.contact.geom[: self.d.ncon] == swing))

    def max_output(self, x: np.ndarray) -> float:
        """The largest ``|y|`` of the virtual constraints over the states ``x`` (rows; rad)."""
        if self.outputs is None or not len(x):
            return float("nan")
        y = self.outputs(*np.asarray(x)[:, : len(COORDINATES)].T, *self.output_params)
        return float(max(np.max(np.abs(v)) for v in y))

    def foot(self, which: int) -> np.ndarray:
        return self.d.site_xpos[self.sites[which]][[0, 2]].copy()


def _limits(system: Any) -> dict[str, float | None]:
    """MuJoCo joint → the torque limit of the input on it (N·m), both legs alike."""
    joints_of = dict(zip(COORDINATES, ("torso", "hip_a", "hip_b", "knee_a", "knee_b")))
    limits: dict[str, float | None] = {}
    for model in system.symbolic().modes.values():
        for a in getattr(model, "actuators", []):
            coord = str(a.on)
            if coord not in COORDINATES[1:]:
                raise ModelError(f"model {system.name!r}: input {a.symbol} must drive one joint coordinate")
            limits[joints_of[coord]] = a.limit
    for s, w in (("a", "b"), ("b", "a")):  # a leg's input has the limit of either role's
        for joint in ("hip", "knee"):
            limits[f"{joint}_{s}"] = limits.get(f"{joint}_{s}") or limits.get(f"{joint}_{w}")
    return limits


def replay_in_mujoco(system: Any, steps: int = 10, *, params: Mapping[str, float] | None = None,
                     x0: Sequence[float] | None = None, timestep: float = TIMESTEP, contact_time: float = CONTACT_TIME,
                     foot_radius: float = 0.005, friction: float = 1.0) -> MujocoReplay:
    """Walk ``steps`` footfalls of a planar biped (RABBIT's layout) in MuJoCo under amble's control
    law, from amble's post-impact state ``x0`` (default: the system's start, the gait's fixed point
    for ``rabbit``) with the stance foot at the origin, and compare each step with amble's run
    from the same state (:class:`StepDrift`). MuJoCo's contact is soft (a spring-damper of time
    constant ``contact_time``, s, and MuJoCo's default ``solimp``), its integrator
    ``implicitfast`` with step ``timestep`` (s); see :func:`planar_biped_mjcf` for
    ``foot_radius`` and ``friction``.
    """
    if not 1 <= int(steps) <= 10000:
        raise ParameterError(f"steps must be at least 1 and at most 10000, got {steps}")
    values = _values(system, params)
    if x0 is None and system.mode_names[0] not in system.default_start:
        raise ParameterError(f"model {system.name!r} declares no start: give x0")
    x0 = np.asarray(system.default_start[system.mode_names[0]] if x0 is None else x0, dtype=float)
    if x0.shape != (2 * len(COORDINATES),):
        raise ParameterError(f"x0 must have {2 * len(COORDINATES)} values (state_names order), got {x0.size}")
    limits = _limits(system)
    xml = planar_biped_mjcf(system, values, foot_radius=foot_radius, friction=friction, timestep=timestep,
                            contact_time=contact_time, limits=limits)
    walk = _Walk(system, values, xml, x0)
    walk.check(system)
    ref = _Reference(system, x0, values, steps, timestep)
    bound = np.array([limits.get(MUJOCO_JOINTS[i]) or np.inf for i in range(3, len(MUJOCO_JOINTS))])
    return _walk(walk, ref, steps, bound, xml)


def _walk(walk: _Walk, ref: _Reference, steps: int, bound: np.ndarray, xml: str) -> MujocoReplay:
    """MuJoCo's steps one after the other, each compared with amble's when its footfall comes."""
    hip_height = float(walk.d.site_xpos[walk.hip, 2])
    patience = 3.0 * ref.mean_step_time()
    shortest = 0.2 * ref.mean_step_time()  # a touch sooner is the swing foot leaving, not landing
    dt = float(walk.m.opt.timestep)
    drift: list[StepDrift] = []
    t_step, samples_t, samples_q = 0.0, [], []
    stance_start, deepest, max_u, status = walk.foot(0), 0.0, 0.0, "completed"
    x, clipped = walk.state(), 0
    while len(drift) < steps:
        u = np.abs(walk.control(x))
        max_u = max(max_u, float(u.max()))
        clipped += bool(np.any(u > bound[np.asarray(walk.motor[walk.stance])]))
        walk.mj.mj_step(walk.m, walk.d)
        t, x = float(walk.d.time), walk.state()
        samples_t.append(t - t_step)
        samples_q.append(x)
        deepest = max(deepest, -float(walk.foot(walk.stance)[1]))
        if walk.d.site_xpos[walk.hip, 2] < 0.5 * hip_height or abs(x[0]) > np.pi / 2 or t - t_step > patience:
            status = "fell"
            break
        if t - t_step < shortest or not walk.touchdown():
            continue
        k = len(drift)
        swing, stance = walk.foot(1 - walk.stance), walk.foot(walk.stance)
        xs = np.asarray(samples_q)
        rms = ref.angle_rms(k, np.asarray(samples_t), xs[:, : len(COORDINATES)])
        drift.append(StepDrift(k, t - t_step, ref.step(k)[0], float(swing[0] - stance[0]), ref.step(k)[1], rms,
                               float(abs(stance[0] - stance_start[0])), deepest, walk.max_output(xs)))
        walk.stance = 1 - walk.stance
        x = walk.state()
        t_step, samples_t, samples_q, stance_start, deepest = t, [], [], swing, 0.0
    return MujocoReplay(status, len(drift), drift, max_u, clipped * dt, float(walk.d.time), xml)
