"""MJCF import: a MuJoCo model file as a model with a rigid-body tree.

The file is read by MuJoCo's own compiler (``mujoco.MjModel.from_xml_path``), so that defaults
classes, ``<include>``, inertias computed from geoms, ``autolimits`` and angle units mean what they
mean to MuJoCo. The compiled model's body tree is then read — ``body_parentid``, ``body_pos`` /
``body_quat`` (the body frame in its parent's), ``body_mass``, ``body_ipos``, the principal
``body_inertia`` with its frame ``body_iquat`` — and each joint of a body becomes a joint of the
:class:`~amble.modelling.tree.RigidTree`, in MuJoCo's order:

* a ``hinge`` turns about ``jnt_axis`` through ``jnt_pos`` (both in the body frame), a ``slide``
  moves along ``jnt_axis``; the coordinate, named as the joint, is MuJoCo's ``qpos − qpos0``
  (``qpos0`` is the joint's ``ref``, usually 0), rad or m. A body with several joints gets them
  one after the other, through massless frames, as MuJoCo composes them;
* a ``free`` joint (a body of the world only) is a ``floating`` tree joint: translations of the
  body origin along the world axes from its position in the file, then yaw, pitch, roll about
  world z, y, x applied to its orientation in the file (``R = Rz Ry Rx R_file``); zero is the
  pose of the file. Coordinates ``<joint>_x`` … ``<joint>_roll`` (the body's name if the joint
  has none). With ``fixed_base=True`` the body is welded to the world at that pose;
* a ``ball`` joint is a ``spherical`` tree joint about ``jnt_pos``: yaw, pitch, roll about the
  body's axes (zero: the file's pose);
* a body without joints is fixed to its parent (a body of the world without joints: to the world).

MuJoCo's velocity coordinates of free and ball joints (the angular velocity in the body frame
with a quaternion position) are not amble's (Euler angle rates): the equations are the same
mechanics in other coordinates, ``M = Jᵀ M_mj J``, with ``J = ∂v_mj/∂q̇``.

Passive joint properties of the file are part of the equations: ``damping`` ``d`` is the
generalised force ``−d q̇`` on the joint's coordinate, ``stiffness`` ``k`` the potential
``k (q − (springref − ref))² / 2``, ``armature`` ``a`` the kinetic energy ``a q̇² / 2`` (it adds
``a`` to the diagonal of ``M``, as in MuJoCo). ``frictionloss`` is ignored with a warning, and so
are actuators, tendons without stiffness or damping, inactive equality constraints and fluid
forces (``density``, ``viscosity``, ``wind``); contacts are not read (the model has no ground).
A linear ``<equality><joint>`` between two hinges or slides, ``θ₁ = c0 + c1 θ₂``, is a mimic
joint of the tree (:mod:`amble.modelling.tree`): the joint read later follows the other, with one
coordinate fewer (MuJoCo holds the same relation by a stiff constraint force). An
``<equality><connect>`` of two bodies (a closed loop) is a holonomic constraint of the model
(:meth:`~amble.modelling.model.Model.holonomic`), exact where MuJoCo's is soft.
Refused with a one-line :class:`~amble.errors.ModelError` naming the element: any other active
equality constraint (a weld, a connect of sites, a tendon or polynomial coupling), a tendon with
stiffness or damping, gravity compensation, damping, armature or stiffness on a free or ball
joint, a free joint below another body, flexible bodies, and a file that MuJoCo's compiler
refuses (its message is given).
Gravity is ``opt.gravity`` (any direction).
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from ..errors import ModelError
from .bodies import Joint
from .dag import free_symbols

#: MuJoCo's joint types (``mjtJoint``)
_FREE, _BALL, _SLIDE, _HINGE = 0, 1, 2, 3


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError as e:  # pragma: no cover - a declared dependency of the extra
        raise ModelError("MJCF import needs the 'mujoco' package: pip install 'amble[mjcf]'") from e
    return mujoco


def compile_file(source: Any) -> Any:
    """MuJoCo's compiled ``MjModel`` of the MJCF file ``source`` (a path) — its compiler's
    refusal as a one-line :class:`ModelError`."""
    mujoco = _mujoco()
    path = Path(source)
    if not path.is_file():
        raise ModelError(f"robot file {str(path)!r} does not exist")
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except Exception as e:  # MuJoCo's XML and compiler errors (ValueError), one line
        text = " ".join(str(e).split())
        raise ModelError(f"MJCF {path.name}: MuJoCo cannot compile it: {text}") from None


def _name(m: Any, kind: Any, i: int, default: str) -> str:
    mujoco = _mujoco()
    raw = mujoco.mj_id2name(m, kind, i)
    return re.sub(r"\W", "_", raw) if raw else default


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion ``(w, x, y, z)`` (MuJoCo's order)."""
    w, x, y, z = (float(v) for v in q / np.linalg.norm(q))
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _check_whole(m: Any, label: str) -> tuple[dict[int, tuple[int, float, float]], list[tuple]]:
    """Refuse what the tree cannot hold; warn about what it leaves out. Returns the joints tied
    to another by a linear ``<equality><joint>`` (``{follower: (joint followed, c1, c0)}``) and
    the ``<equality><connect>`` of two bodies (``(name, body 1, anchor 1, body 2, anchor 2)``)."""
    mujoco = _mujoco()
    eq_names = {0: "connect", 1: "weld", 2: "joint", 3: "tendon", 4: "flex", 5: "distance"}
    inactive, ties, connects = [], {}, []
    for i in range(m.neq):
        kind = eq_names.get(int(m.eq_type[i]), "equality")
        nm = _name(m, mujoco.mjtObj.mjOBJ_EQUALITY, i, f"#{i}")
        if not bool(m.eq_active0[i]):
            inactive.append(nm)
            continue
        if kind == "connect" and int(getattr(m, "eq_objtype", [mujoco.mjtObj.mjOBJ_BODY] * m.neq)[i]) == \
                mujoco.mjtObj.mjOBJ_BODY:
            data = np.asarray(m.eq_data[i][:6], dtype=float)
            connects.append((nm, int(m.eq_obj1id[i]), data[:3], int(m.eq_obj2id[i]), data[3:6]))
            continue
        tie = _joint_tie(m, i) if kind == "joint" else None
        if tie is None:
            raise ModelError(f"MJCF {label}: equality constraint <{kind}> {nm!r} is active: welds and "
                             "couplings other than a linear one of two hinges or slides are not read")
        if tie[0] in ties:
            raise ModelError(f"MJCF {label}: equality constraint <joint> {nm!r}: joint 1 is tied twice")
        ties[tie[0]] = tie[1:]
    if inactive:
        warnings.warn(f"MJCF {label}: inactive equality constraints ignored: {', '.join(inactive)}", stacklevel=3)
    _check_passive(m, label)
    return ties, connects


def _check_passive(m: Any, label: str) -> None:
    mujoco = _mujoco()
    if getattr(m, "nflex", 0):
        raise ModelError(f"MJCF {label}: flexible bodies (<flex>) are not supported")
    for i in range(m.ntendon):
        if m.tendon_stiffness[i] != 0 or m.tendon_damping[i] != 0:
            nm = _name(m, mujoco.mjtObj.mjOBJ_TENDON, i, f"#{i}")
            raise ModelError(f"MJCF {label}: tendon {nm!r} has stiffness or damping: tendon forces are not read")
    for b in range(1, m.nbody):
        if m.body_gravcomp[b] != 0:
            nm = _name(m, mujoco.mjtObj.mjOBJ_BODY, b, f"body{b}")
            raise ModelError(f"MJCF {label}: body {nm!r} has gravcomp: gravity compensation is not supported")
    left_out = [what for what, n in (("actuators", m.nu), ("tendons", m.ntendon)) if n]
    if m.opt.density != 0 or m.opt.viscosity != 0 or np.any(m.opt.wind != 0):
        left_out.append("fluid forces (density, viscosity, wind)")
    if np.any(m.dof_frictionloss != 0):
        left_out.append("joint frictionloss")
    if left_out:
        warnings.warn(f"MJCF {label}: ignored: {', '.join(left_out)}", stacklevel=4)


def _joint_tie(m: Any, i: int) -> tuple[int, int, float, float] | None:
    """``(follower, joint followed, k, c)`` of an equality ``θ₁ = c0 + c1 θ₂`` between two hinge or
    slide joints (MuJoCo's ``polycoef`` with no quadratic or higher term; both angles from
    ``qpos0``), with ``θ_follower = k θ_followed + c`` and the follower read after the joint it
    follows: the tree's mimic joint, held exactly where MuJoCo holds it by a stiff constraint force."""
    j1, j2 = int(m.eq_obj1id[i]), int(m.eq_obj2id[i])
    coef = np.asarray(m.eq_data[i][:5], dtype=float)
    one_axis = (_HINGE, _SLIDE)
    if j2 < 0 or m.jnt_type[j1] not in one_axis or m.jnt_type[j2] not in one_axis or np.any(coef[2:] != 0):
        return None
    c0, c1 = float(coef[0]), float(coef[1])
    if j2 < j1:  # joints are numbered from the world outwards: the one followed is declared first
        return j1, j2, c1, c0
    if c1 == 0.0:  # joint 1 held at c0 by a joint read after it: a locked joint, not a coupling
        return None
    return j2, j1, 1.0 / c1, -c0 / c1  # θ₂ = (θ₁ − c0) / c1


def _inertial(m: Any, b: int) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre of mass (body frame) and inertia about it (body axes) of body ``b``."""
    Ri = _quat_matrix(m.body_iquat[b])
    return float(m.body_mass[b]), np.array(m.body_ipos[b], dtype=float), Ri @ np.diag(m.body_inertia[b]) @ Ri.T


def _passive(ctx: dict, model: Any, j: int, body: Any, what: str) -> None:
    """The joint's damping, stiffness and armature as a force, a potential and a kinetic term, on
    the joint's angle ``θ = k a + c`` (``k = 1``, ``c = 0`` but for a tied joint) of the model
    coordinate ``a``: ``−d k² ȧ``, ``k_s (θ − θ_spring)²/2``, ``arm k² ȧ²/2``."""
    m = ctx["m"]
    d = int(m.jnt_dofadr[j])
    damping, armature, stiffness = float(m.dof_damping[d]), float(m.dof_armature[d]), float(m.jnt_stiffness[j])
    qa = int(m.jnt_qposadr[j])
    if m.jnt_type[j] in (_FREE, _BALL):
        n = 6 if m.jnt_type[j] == _FREE else 3
        if np.any(m.dof_damping[d:d + n] != 0) or np.any(m.dof_armature[d:d + n] != 0) or stiffness != 0:
            raise ModelError(f"MJCF {ctx['label']}: {what} has damping, armature or stiffness, which are read on "
                             "hinge and slide joints only")
        return
    if damping:  # applied once every coordinate is declared (a force has one entry per coordinate)
        ctx["damping"].append((body, damping))
    if armature:
        model.add_kinetic(armature * body.rate**2 / 2)
    if stiffness:
        rest = float(m.qpos_spring[qa]) - float(m.qpos0[qa])
        model.add_potential(stiffness * (body.coordinate - rest) ** 2 / 2)


def _limits(m: Any, j: int) -> dict[str, float | None]:
    if not m.jnt_limited[j] or m.jnt_type[j] not in (_HINGE, _SLIDE):
        return {"lower": None, "upper": None}
    ref = float(m.qpos0[m.jnt_qposadr[j]])
    return {"lower": float(m.jnt_range[j, 0]) - ref, "upper": float(m.jnt_range[j, 1]) - ref}


def _body_joints(ctx: dict, b: int, bname: str, parent: str | None) -> list[tuple]:
    """The tree joints of MuJoCo body ``b``: ``(joint, coordinate name, MuJoCo joint id)`` each,
    the first placing the body frame in its parent's (``body_pos``, ``body_quat``)."""
    m, label, fixed_base = ctx["m"], ctx["label"], ctx["fixed_base"]
    mujoco = _mujoco()
    pos, Ro = np.array(m.body_pos[b], dtype=float), _quat_matrix(m.body_quat[b])
    adr, num = int(m.body_jntadr[b]), int(m.body_jntnum[b])
    if num == 0:
        return [(Joint("fixed", xyz=tuple(pos), rotation=Ro), None, None)]
    out = []
    for k, j in enumerate(range(adr, adr + num)):
        jname = ctx["joint_names"].setdefault(
            j, _name(m, mujoco.mjtObj.mjOBJ_JOINT, j, f"{bname}_joint{k}" if num > 1 else bname))
        kind = int(m.jnt_type[j])
        first = k == 0
        p = np.array(m.jnt_pos[j], dtype=float)
        if kind == _FREE:
            if parent is not None:
                raise ModelError(f"MJCF {label}: free joint {jname!r} of body {bname!r} is not on a body of "
                                 "the world")
            if fixed_base:
                out.append((Joint("fixed", xyz=tuple(pos), rotation=Ro), None, j))
            else:
                ctx["free"].append(jname)
                out.append((Joint("floating", xyz=tuple(pos), rotation=np.eye(3), post_rotation=Ro), jname, j))
            continue
        xyz, rot = (pos + Ro @ p, Ro) if first else (p, np.eye(3))
        tie = {}
        if j in ctx["ties"]:
            ref, k1, c0 = ctx["ties"][j]
            tie = dict(mimic=ctx["joint_names"][ref], multiplier=k1, offset=c0)
        if kind == _BALL:
            joint = Joint("spherical", xyz=tuple(xyz), rotation=rot, post_xyz=tuple(-p))
        elif kind == _SLIDE:
            joint = Joint("prismatic", axis=tuple(m.jnt_axis[j]), xyz=tuple(pos) if first else (0.0, 0.0, 0.0),
                          rotation=rot, **_limits(m, j), **tie)
        else:
            joint = Joint("revolute", axis=tuple(m.jnt_axis[j]), xyz=tuple(xyz), rotation=rot,
                          post_xyz=tuple(-p), **_limits(m, j), **tie)
        out.append((joint, jname, j))
    return out


def _connect(model: Any, label: str, name: str, body1: str, anchor1: np.ndarray, body2: str | None,
             anchor2: np.ndarray) -> None:
    """An ``<equality><connect>``: the anchor on ``body1`` (its frame) held at the anchor on
    ``body2`` (its frame; the world's for ``None``) — MuJoCo computes the second from the first in
    the file's pose, so the file's pose closes the loop. The components of ``p₁ − p₂`` that no
    coordinate moves (the normal of a planar loop) are left out: they would make the constraint
    Jacobian rank-deficient."""
    tree = model.tree
    p1 = tree.position(body1, tuple(anchor1))
    p2 = tree.position(body2, tuple(anchor2)) if body2 is not None else sp.Matrix([float(v) for v in anchor2])
    coords = set(model.q)
    rows = [e for e in p1 - p2 if free_symbols(e) & coords]
    if not rows:
        raise ModelError(f"MJCF {label}: equality constraint <connect> {name!r} joins points that no joint moves")
    model.holonomic(name, rows)


def _joint_names(m: Any) -> dict[int, str]:
    """The joints' names (characters other than letters, digits and ``_`` as ``_``); unnamed joints
    are named when their body is read."""
    mujoco = _mujoco()
    return {j: _name(m, mujoco.mjtObj.mjOBJ_JOINT, j, "") for j in range(m.njnt)
            if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)}


def build_model(cls: type, path: Any, name: str | None = None, fixed_base: bool = False,
                contact_points: Mapping | None = None) -> Any:
    """A model (of class ``cls``) of the MJCF file at ``path`` (module docstring); every coordinate
    zero is the file's reference pose (``qpos0``). ``fixed_base`` welds free bodies to the world
    where the file places them; ``contact_points`` name further points ``{name: (body, (x, y, z))}``
    in the body's frame."""
    path = Path(path)
    m = compile_file(path)
    mujoco = _mujoco()
    label = path.name
    ties, connects = _check_whole(m, label)
    model = cls(name or _name(m, mujoco.mjtObj.mjOBJ_MODEL, 0, "") or path.stem, dims=3)
    g = np.array(m.opt.gravity, dtype=float)
    gn = float(np.linalg.norm(g))
    model.gravity(gn, direction=list(g / gn) if gn else None)
    tree = model.rigid_tree()
    ctx = {"m": m, "label": label, "fixed_base": fixed_base, "free": [], "damping": [], "ties": ties,
           "joint_names": _joint_names(m)}
    names: dict[int, str] = {0: None}
    for b in range(1, m.nbody):
        bname = _name(m, mujoco.mjtObj.mjOBJ_BODY, b, f"body{b}")
        parent = names[int(m.body_parentid[b])]
        mass, com, inertia = _inertial(m, b)
        joints = _body_joints(ctx, b, bname, parent)
        for k, (joint, coord, j) in enumerate(joints):
            if k == len(joints) - 1:
                body = tree.body(bname, parent=parent, joint=joint, mass=mass, com=com, inertia=inertia,
                                 coordinate=coord)
                frame = bname
            else:  # a massless frame between two joints of one body
                frame = f"{bname}.{coord}"
                if joint.type == "spherical":
                    body = tree.body(frame, parent=parent, joint=joint, coordinate=coord)
                else:
                    body = tree._add(frame, parent, joint, 0, (0, 0, 0), ((0, 0, 0),) * 3, coord, None,
                                     internal=True)
                    model.touch()
            if j is not None and coord is not None:
                _passive(ctx, model, j, body, f"joint {coord!r}")
            parent = frame
        names[b] = bname
    tree.joint_damping(ctx["damping"])
    for nm, b1, a1, b2, a2 in connects:
        _connect(model, label, nm, names[b1], a1, names[b2], a2)
    tree.file = path
    for pname, spec in (contact_points or {}).items():
        try:
            body, at = spec
        except (TypeError, ValueError):
            raise ModelError(f"contact point {pname!r}: give (body, (x, y, z)), got {spec!r}") from None
        tree.point(pname, body, at)
    return model
