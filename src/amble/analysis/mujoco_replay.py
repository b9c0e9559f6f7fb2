"""A planar biped and its controlled gait in MuJoCo: the robot as MJCF, soft ground contact, amble's
control law in MuJoCo's loop, and the drift between the two runs per step.

amble's walker is pinned at its stance foot and its footfall is an instantaneous plastic impact;
MuJoCo's robot is free in the sagittal plane (a *planar root*: ``rootx`` slides along x,
``rootz`` along z, the hinge ``torso`` turns about +y) and stands on the ground through a soft,
penetrable contact with friction. Replaying the same control law in both tells how much of a gait
survives soft contacts before it is tried on hardware.

The control law is amble's compiled one: at every MuJoCo step the state is read in amble's
coordinates (stance leg first) and the generalized force ``Γ + B u`` of the compiled model is
applied through one motor per actuated joint (``ctrl`` = ``u``, clipped to the declared limits).
A footfall in MuJoCo is the swing foot touching the ground ahead of the stance foot.

The robot's MJCF and its change of coordinates are :mod:`amble.analysis.mujoco_biped`, the
drift per step and the outcome :mod:`amble.analysis.mujoco_drift` (re-exported here).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import ModelError, ParameterError
from .defaults import MUJOCO_CONTACT_TIME as CONTACT_TIME
from .defaults import MUJOCO_TIMESTEP as TIMESTEP
from .mujoco_biped import (
    COORDINATES,
    MUJOCO_JOINTS,
    _joint_order,
    _values,
    amble_state,
    mujoco_state,
    planar_biped_mjcf,
)
from .mujoco_drift import MujocoReplay, StepDrift, _Reference

__all__ = ["COORDINATES", "MUJOCO_JOINTS", "MujocoReplay", "StepDrift", "amble_state", "mujoco_state",
           "planar_biped_mjcf", "replay_in_mujoco"]


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError as e:  # pragma: no cover - a declared dependency of the extra
        raise ModelError("the MuJoCo export needs the 'mujoco' package: pip install 'amble[mjcf]'") from e
    return mujoco


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
