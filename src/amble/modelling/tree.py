"""Rigid bodies and joints: a kinematic tree as a modelling object.

A :class:`RigidTree` belongs to a :class:`~amble.modelling.model.Model` (``model.rigid_tree()``).
Each :class:`Body` hangs from a parent body (or from the fixed base) by a :class:`Joint`:

* ``revolute`` about a unit ``axis`` (``continuous`` is a revolute joint without limits),
* ``prismatic`` along a unit ``axis``,
* ``fixed`` (no coordinate).

A revolute or prismatic joint may **mimic** a coordinate of the model (``Joint(mimic="a",
multiplier=k, offset=c)``, the URDF ``<mimic>``): its angle (or travel) is ``k·a + c`` and it has
no coordinate of its own — a gripper's fingers driven by one motor. The tree then has one
coordinate fewer and its equations are the reduced ones: with ``G = ∂q_joints/∂q`` (constant),
``M = Gᵀ M_joints G`` and ``h = Gᵀ h_joints``, which the recursions produce directly because the
joint's motion subspace per unit of ``ȧ`` is ``k`` times its own (:meth:`RigidTree.local_subspace`).

A joint has an origin in its parent's frame — a translation ``xyz`` and a rotation ``rpy``
(roll, pitch, yaw about fixed x, y, z: ``R = Rz(yaw) Ry(pitch) Rx(roll)``), the URDF conventions —
and the joint motion follows the origin. The body has a mass, a centre of mass and a full 3×3
inertia tensor about the centre of mass, both in the body frame (numbers or expressions of the
model's parameters).

Each moving joint's coordinate becomes a model coordinate; each body's centre of mass becomes a
named point carrying its mass, and :meth:`RigidTree.point` names further points on bodies — so
guards, impacts and drawing see an ordinary model. The world-frame kinematics are built by
recursion over the tree, each body from its parent only: ``Rᵢ = R_parent Xᵢ(qᵢ)``,
``pᵢ = p_parent + R_parent oᵢ``, ``ωᵢ = ω_parent + q̇ᵢ zᵢ``, … — expressions that share their
parents' and are never differentiated (:mod:`amble.derivation.tree` builds ``M`` and ``h`` from them).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp

from ..errors import ModelError
from .bodies import _COMPOSITE, JOINT_TYPES, Body, Joint
from .defs import Defs
from .sparse_algebra import _cross, _dot, _mat3, _matmul, _mul_add, _num, _rotation, _vec, rpy_matrix
from .text import expr_of

__all__ = ["JOINT_TYPES", "Body", "Joint", "RigidTree", "rpy_matrix"]


class RigidTree:
    """A kinematic tree of rigid bodies in a 3D model (created by ``Model.rigid_tree()``)."""

    def __init__(self, model: Any) -> None:
        if model.dims != 3:
            raise ModelError(f"model {model.name!r}: a rigid-body tree needs a 3D model (dims=3)")
        self.model = model
        self.bodies: list[Body] = []
        self._by_name: dict[str, Body] = {}
        #: names of the model points that are body centres of mass (their masses are the bodies')
        self.com_points: dict[str, Body] = {}
        #: velocity of each point defined on a body, by point name (no differentiation needed)
        self.point_velocities: dict[str, sp.Matrix] = {}
        #: the body of each named point and its offset from the body origin (world axes, named)
        self.point_frames: dict[str, tuple[Body, sp.Matrix]] = {}
        #: the range ``(lower, upper)`` of each joint coordinate (rad or m; ``None``: unbounded
        #: that way); a mimic joint's is not the model's (:mod:`amble.modelling.limits`)
        self.limits: dict[str, tuple[float | None, float | None]] = {}
        #: the robot file the tree was read from (None when built in code), for drawing its meshes
        self.file: Any = None
        #: links of the file that are no body (massless, on a fixed joint): link → (body it is
        #: fixed to (None: the world), rotation of the link frame in the body's, origin in it, m)
        self.link_frames: dict[str, tuple[str, np.ndarray, tuple]] = {}
        #: intermediate quantities of the recursions (body kinematics here, dynamics in derivation)
        self.defs = Defs()
        self._energies: dict[tuple, sp.Expr] = {}

    # ------------------------------------------------------------------ building
    def body(self, name: str, parent: str | None = None, joint: Joint | None = None, mass: Any = 0,
             com: Sequence[Any] = (0, 0, 0), inertia: Any = ((0, 0, 0), (0, 0, 0), (0, 0, 0)),
             coordinate: str | None = None, unit: str | None = None) -> Body:
        """Add a body hanging from ``parent`` (``None``: the fixed base) by ``joint``.

        A moving joint declares the model coordinate ``coordinate`` (default: the body's name),
        in rad for a revolute joint and m for a prismatic one. The centre of mass becomes the
        model point ``name`` carrying ``mass``.

        A ``spherical`` joint (3 coordinates ``<coordinate>_yaw``, ``_pitch``, ``_roll``: the
        rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` of the joint frame) and a ``floating`` one (6:
        ``<coordinate>_x``, ``_y``, ``_z`` along the joint frame's axes, then yaw, pitch, roll)
        are chains of one-axis joints through massless frames — Euler angles, singular at
        pitch = ±π/2 (gimbal lock), which a walker's base does not reach. Their ``post_xyz`` /
        ``post_rotation`` place the body after the last rotation: a point foot pivoting at its
        sole, ``Joint("spherical", post_xyz=(0, 0, 0.06))`` for a foot frame 6 cm above the sole.
        """
        joint = joint or Joint()
        m = self.model
        if name in self._by_name:
            raise ModelError(f"model {m.name!r}: body {name!r} defined twice")
        if joint.type not in JOINT_TYPES:
            raise ModelError(f"model {m.name!r}: joint of body {name!r} has unknown type {joint.type!r} "
                             f"(known: {', '.join(JOINT_TYPES)})")
        if joint.mimic is not None and joint.type not in ("revolute", "continuous", "prismatic"):
            raise ModelError(f"model {m.name!r}: joint of body {name!r} is {joint.type}: only a revolute or "
                             "prismatic joint can mimic a coordinate")
        if joint.type in _COMPOSITE:
            cname = coordinate or name
            *inner, last = _COMPOSITE[joint.type]
            for k, (suffix, kind, axis) in enumerate(inner):
                first = dict(xyz=joint.xyz, rpy=joint.rpy, rotation=joint.rotation) if k == 0 else {}
                self._add(f"{name}.{suffix}", parent, Joint(kind, axis=axis, **first), 0, (0, 0, 0),
                          ((0, 0, 0),) * 3, f"{cname}_{suffix}", None, internal=True)
                parent = f"{name}.{suffix}"
            suffix, kind, axis = last
            joint = Joint(kind, axis=axis, lower=joint.lower, upper=joint.upper,
                          post_xyz=joint.post_xyz, post_rotation=joint.post_rotation)
            coordinate = f"{cname}_{suffix}"
        body = self._add(name, parent, joint, mass, com, inertia, coordinate, unit)
        self.model.touch()  # the tree is part of its model's declaration: a built system sees the body
        return body

    def _add(self, name: str, parent: str | None, joint: Joint, mass: Any, com: Sequence[Any], inertia: Any,
             coordinate: str | None, unit: str | None, internal: bool = False) -> Body:
        """A body of a one-axis (or fixed) joint; ``internal``: a massless frame of a composite
        joint, which is not a model point."""
        m = self.model
        par = None
        if parent is not None:
            if parent not in self._by_name:
                raise ModelError(f"model {m.name!r}: body {name!r} hangs from unknown body {parent!r}")
            par = self._by_name[parent]
        mass_e = (_num(mass) if isinstance(mass, (int, float))
                  else expr_of(mass, m.symbol_table(), what=f"model {m.name!r}: mass of body {name!r}"))
        m._check_symbols(mass_e, f"mass of body {name!r}")
        b = Body(name=name, parent=par, joint=joint, mass=mass_e, com=_vec(com), inertia=_mat3(inertia))
        if b.com.shape != (3, 1):
            raise ModelError(f"model {m.name!r}: centre of mass of body {name!r} needs 3 components")
        self._check_inertial(b)
        if joint.type != "fixed":
            a = np.asarray([float(v) for v in joint.axis])
            na = float(np.linalg.norm(a))
            if a.shape != (3,) or na == 0.0:
                raise ModelError(f"model {m.name!r}: joint of body {name!r} needs a nonzero 3D axis")
            joint.axis = tuple(a / na)
            if joint.mimic is not None:
                self._mimic(b)
            else:
                cname = coordinate or name
                (b.coordinate,) = m.coordinates([cname], unit=unit or ("m" if joint.type == "prismatic" else "rad"))
                b.index = m.q.index(b.coordinate)
                b.rate = m.dot(b.coordinate)
                # a continuous joint has no range whatever limits it is given (URDF ignores them too)
                self.limits[cname] = (None, None) if joint.type == "continuous" else (joint.lower, joint.upper)
        self._kinematics(b)
        self.bodies.append(b)
        self._by_name[name] = b
        if internal:
            return b
        r = self.defs.vec(_matmul(b.R, b.com))
        m.point(name, self.defs.expand(b.p + r))
        self.point_velocities[name] = self.defs.expand(b.vel + b.omega.cross(r))
        self.point_frames[name] = (b, r)
        self.com_points[name] = b
        if mass_e != 0:
            m.mass(name, mass_e)
        while par is not None and par.name not in m.points:  # past a composite joint's frames
            par = par.parent
        if par is not None:
            m.link(par.name, name)
        return b

    def _mimic(self, b: Body) -> None:
        """Tie a mimic joint to its model coordinate ``a``: angle ``k·a + c``, rate ``k·ȧ``."""
        m, j = self.model, b.joint
        ref = next((s for s in m.q if str(s) == j.mimic), None)
        if ref is None:
            raise ModelError(f"model {m.name!r}: joint of body {b.name!r} mimics {j.mimic!r}, which is not a "
                             "coordinate of the model (declare the joint it follows first)")
        k, c = float(j.multiplier), float(j.offset)
        if not (math.isfinite(k) and math.isfinite(c)):
            raise ModelError(f"model {m.name!r}: joint of body {b.name!r}: mimic multiplier {k:g} and offset {c:g} "
                             "must be finite")
        b.multiplier = _num(k)
        b.coordinate = b.multiplier * ref + _num(c)
        b.index = m.q.index(ref)
        b.rate = b.multiplier * m.dot(ref)

    def _check_inertial(self, b: Body) -> None:
        """:class:`ModelError` naming the body for a negative or non-finite numeric mass (zero is
        a massless frame: a composite joint's, or a link without an inertial) or a non-finite
        numeric entry of its centre of mass or inertia tensor; a symbolic mass makes its
        parameter's domain positive (:meth:`Model._check_mass`). Positive definiteness is not
        asked: a link of zero inertia is a point mass."""
        m = self.model
        m._check_mass(b.mass, f"mass of body {b.name!r}", zero=True)
        for what, entries in (("centre of mass", b.com), ("inertia", b.inertia)):
            bad = [e for e in entries if e.is_number and not (e.is_finite and e.is_extended_real)]
            if bad:
                raise ModelError(f"model {m.name!r}: {what} of body {b.name!r} has a non-finite entry {bad[0]}")

    def position(self, body: str, at: Sequence[Any] = (0, 0, 0)) -> sp.Matrix:
        """World position of the point ``at`` (body frame) of ``body``, without naming it (a loop
        closure's anchor: ``Model.holonomic``)."""
        if body not in self._by_name:
            raise ModelError(f"model {self.model.name!r}: no body named {body!r}")
        b = self._by_name[body]
        return self.defs.expand(b.p + self.defs.vec(_matmul(b.R, _vec(at))))

    def point(self, name: str, body: str, at: Sequence[Any] = (0, 0, 0)) -> sp.Matrix:
        """Name a point fixed on ``body`` at ``at`` (body frame); returns its world position."""
        if body not in self._by_name:
            raise ModelError(f"model {self.model.name!r}: point {name!r} on unknown body {body!r}")
        b = self._by_name[body]
        r = self.defs.vec(_matmul(b.R, _vec(at)))
        pos = self.model.point(name, self.defs.expand(b.p + r))
        self.point_velocities[name] = self.defs.expand(b.vel + b.omega.cross(r))
        self.point_frames[name] = (b, r)
        return pos

    def __getitem__(self, name: str) -> Body:
        return self._by_name[name]

    def joint_damping(self, dampings: Sequence[tuple[Body, Any]]) -> None:
        """Viscous damping ``d`` (N·m·s/rad or N·s/m) of each body's joint as the generalised force
        ``−d θ̇`` on its angle (or travel) ``θ``; by virtual work ``−d k² ȧ`` on the coordinate
        ``a`` of a mimic joint ``θ = k a + c``. Dampings of joints that share a coordinate add up.
        One force of the model (a force has one entry per coordinate), so call it once every
        coordinate is declared."""
        force: dict[int, Any] = {}
        for b, d in dampings:
            force[b.index] = force.get(b.index, 0) - d * b.multiplier * b.rate
        if force:
            self.model.force([force.get(i, 0) for i in range(len(self.model.q))])

    @property
    def moving_bodies(self) -> list[Body]:
        return [b for b in self.bodies if b.moving]

    def kinetic(self) -> sp.Expr:
        """Kinetic energy of the bodies from their body-frame velocities ``(ω, v)`` (``v`` of the
        body's origin): Σ ½ (ωᵀ I_o ω + m |v|² + 2 m c·(v × ω)), ``I_o`` about the origin."""
        key = ("K", len(self.bodies))
        if key in self._energies:
            return self._energies[key]
        d = self.defs
        out = []
        vel = self.body_velocities()
        for b in self.bodies:
            m, h, I = self.body_inertia(b)
            w, v = vel[b.name][:2]
            e = _dot(w, d.vec(_matmul(I, w))) + m * _dot(v, v) + 2 * _dot(h, d.vec(_cross(v, w)))
            if e != 0:
                out.append(d(e))
        self._energies[key] = d.expand(sp.Add(*out) / 2)
        return self._energies[key]

    def body_inertia(self, b: Body) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
        """Mass, first moment ``m c`` and rotational inertia ``I_c + m (|c|² 1 − c cᵀ)`` of ``b``
        about its frame's origin, in its axes (constants of the model)."""
        d, c, m = self.defs, b.com, b.mass
        cc = _dot(c, c)
        I = sp.Matrix(3, 3, lambda i, j: b.inertia[i, j] + m * ((cc if i == j else 0) - c[i] * c[j]))
        return m, d.vec(c * m), d.vec(I)

    def body_velocities(self) -> dict[str, tuple[sp.Matrix, ...]]:
        """Spatial velocity of every body in its own frame, by recursion from the base:
        ``(ω, v, ω_j, v_j)`` — angular velocity, velocity of the origin, and the joint's share
        ``Sᵢ q̇ᵢ`` of both (zero for a fixed joint). Named intermediates of :attr:`defs`, which
        the dynamics (:mod:`amble.derivation.tree`) reuse."""
        key = ("vel", len(self.bodies))
        if key in self._energies:
            return self._energies[key]
        d, out, zero = self.defs, {}, sp.zeros(3, 1)
        for b in self.bodies:
            E, r = (d.vec(x) for x in self.local_transform(b))
            if b.parent is None:
                w, v = zero, zero
            else:
                wp, vp = out[b.parent.name][:2]
                w, v = d.vec(_matmul(E.T, wp)), d.vec(_matmul(E.T, vp + _cross(wp, r)))
            sw = sv = zero
            if b.moving:
                qd = self.model.qd[b.index]
                a, o = self.local_subspace(b)
                sw, sv = d.vec(a * qd), d.vec(o * qd)
                w, v = d.vec(w + sw), d.vec(v + sv)
            out[b.name] = (w, v, sw, sv)
        self._energies[key] = out
        return out

    def potential(self, gravity: sp.Matrix) -> sp.Expr:
        """Gravitational potential energy of the bodies, Σ −m g·c, by recursion in body frames:
        with ``gᵢ = Eᵢᵀ g_parent`` (gravity in body i's axes) and ``zᵢ = z_parent + g_parent·rᵢ``
        (g · the origin of body i), ``−m g·c = −m zᵢ − gᵢ·(m c)`` — three rotated components per
        body instead of every body's world rotation."""
        key = ("V", len(self.bodies), tuple(gravity))
        if key in self._energies:
            return self._energies[key]
        d, out = self.defs, []
        gz: dict[str, tuple[sp.Matrix, sp.Expr]] = {}
        for b in self.bodies:
            E, r = (d.vec(x) for x in self.local_transform(b))
            gp, zp = gz[b.parent.name] if b.parent is not None else (gravity, sp.Integer(0))
            gz[b.name] = g, z = d.vec(_matmul(E.T, gp)), d(zp + _dot(gp, r))
            m, h, _ = self.body_inertia(b)
            e = -m * z - _dot(g, h)
            if e != 0:
                out.append(d(e))
        self._energies[key] = d.expand(sp.Add(*out))
        return self._energies[key]

    # ------------------------------------------------------------------ joint transforms
    def local_transform(self, b: Body) -> tuple[sp.Matrix, sp.Matrix]:
        """``(E, r)``: body ``b``'s frame in its parent's (or the world's), ``x_parent = E x_b + r``
        — the joint origin, the joint motion by ``qᵢ``, then any fixed offset after the motion."""
        j = b.joint
        Ro = _mat3(j.rotation) if j.rotation is not None else _mat3(rpy_matrix(j.rpy))
        E, r = Ro, _vec(j.xyz)
        if j.type == "prismatic":
            r = r + _matmul(Ro, _vec(j.axis) * b.coordinate)
        elif j.type != "fixed":
            E = _matmul(Ro, _rotation(_vec(j.axis), sp.cos(b.coordinate), sp.sin(b.coordinate)))
        if j.post_xyz is not None:
            r = r + _matmul(E, _vec(j.post_xyz))
        if j.post_rotation is not None:
            E = _matmul(E, _mat3(j.post_rotation))
        return E, r

    def local_subspace(self, b: Body) -> tuple[sp.Matrix, sp.Matrix]:
        """The motion subspace of ``b``'s joint in ``b``'s own frame, ``(angular, linear at the
        origin)`` per unit of the rate of the model coordinate ``q[b.index]`` — constant: ``(a, o × a)``
        for a revolute joint about the axis ``a`` through the point ``o``, ``(0, a)`` for a prismatic
        one, times the multiplier of a mimic joint."""
        j = b.joint
        Pt = _mat3(j.post_rotation).T if j.post_rotation is not None else sp.eye(3)
        a = _matmul(Pt, _vec(j.axis))
        if b.multiplier != 1:
            a = a * b.multiplier
        if j.type == "prismatic":
            return sp.zeros(3, 1), a
        o = -_matmul(Pt, _vec(j.post_xyz or (0, 0, 0)))   # the joint's origin, seen from the body
        return a, o.cross(a)

    # ------------------------------------------------------------------ kinematics
    def _kinematics(self, b: Body) -> None:
        j = b.joint
        R0 = b.parent.R if b.parent is not None else sp.eye(3)
        p0 = b.parent.p if b.parent is not None else sp.zeros(3, 1)
        w0 = b.parent.omega if b.parent is not None else sp.zeros(3, 1)
        v0 = b.parent.vel if b.parent is not None else sp.zeros(3, 1)
        Ro = _mat3(j.rotation) if j.rotation is not None else _mat3(rpy_matrix(j.rpy))
        pj = _mul_add(R0, _vec(j.xyz), p0)           # joint frame origin, world
        Rj = self.defs.vec(_matmul(R0, Ro))           # joint frame, world
        vj = v0 + w0.cross(pj - p0)
        if j.type == "fixed":
            R, p, w, v = Rj, pj, w0, vj
        else:
            a = _vec(j.axis)
            z = self.defs.vec(_matmul(Rj, a))
            qi, qdi = b.coordinate, b.rate
            b.axis_w, b.axis_point = z, pj
            if j.type == "prismatic":
                R, p, w, v = Rj, pj + z * qi, w0, vj + w0.cross(z * qi) + z * qdi
            else:
                R = _matmul(Rj, _rotation(a, sp.cos(qi), sp.sin(qi)))
                p, w, v = pj, w0 + z * qdi, vj
        if j.post_xyz is not None or j.post_rotation is not None:
            off = _matmul(R, _vec(j.post_xyz or (0, 0, 0)))
            p = p + off
            v = v + w.cross(off)
            if j.post_rotation is not None:
                R = _matmul(R, _mat3(j.post_rotation))
        d = self.defs
        b.R, b.p, b.omega, b.vel = d.vec(R), d.vec(p), d.vec(w), d.vec(v)
        b.axis_w, b.axis_point = d.vec(b.axis_w), d.vec(b.axis_point)
