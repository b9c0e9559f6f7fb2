"""URDF import: a robot description file as a model with a rigid-body tree.

The file is read with `yourdfpy <https://github.com/clemense/yourdfpy>`_ — maintained, pure
Python on top of lxml, and it parses without loading meshes or building a scene graph (the
alternatives: ``urdfpy`` has had no release since 2020 and pins old dependencies;
``urdf_parser_py`` is tied to ROS packaging). Only the parsed elements are used: links with their
inertials, joints with their type, origin, axis, limits and ``<dynamics damping>`` (the generalised
force ``−d θ̇``; Coulomb ``friction`` and ``<transmission>`` elements are ignored with a warning,
:func:`_joint_dynamics`). Everything is then checked here, and
a bad file raises :class:`~amble.errors.ModelError` naming the link or joint:

* a joint of a type other than revolute, continuous, prismatic or fixed (``floating`` and
  ``planar`` included: the base is chosen, not floating),
* a file that is not well-formed XML (cut short, a NUL byte), two links or joints of one name,
  a ``<mimic>`` of a joint the file does not declare — found by a strict parse before the
  parser's own, which recovers from them silently,
* a link reached twice (a kinematic loop, or a link with two parents),
* a link moved by a joint without an inertial or with zero mass and inertia (unless
  ``allow_massless=True``: a massless link with massive links below it), a negative or
  non-finite mass, an inertia tensor that is not finite, not symmetric, has a clearly negative
  principal moment, or whose principal moments break the triangle inequality — each to a relative
  1e-9 of the larger of the tensor's size and ``mass · (1 mm)²``, so that a thin rod, a point
  mass and rounding (``-2e-22`` next to ``3e-6``) load (:func:`_check_inertial`),
* a ``<mimic>`` that follows a fixed joint, a joint below it, or a loop of mimics.

A ``<mimic joint="a" multiplier="k" offset="c"/>`` joint has no coordinate: its angle is
``k·a + c`` (a chain of mimics resolved), and the tree's equations are the reduced ones
(:mod:`amble.modelling.tree`). A massless link on a fixed joint (a sensor or tool frame) is no
body: it is a point of the body it hangs from, named as the link, and what hangs from it is placed
through it (Pinocchio merges fixed joints the same way).

The user chooses the base link, fixed to the world (e.g. the stance foot): the tree is re-rooted
there, joints between the base and the URDF root are traversed backwards (the same joint
coordinate, motion inverted). Joint coordinates are named as the joints, the centre of mass of
each link is a model point named as the link, and ``contact_points`` name further points:
``{"heel": ("left_foot", (0.0, 0.0, -0.05))}``.

Masses, centres of mass, inertias and joint offsets are constants of the compiled model unless
``parameters`` asks for them as named model parameters (run-time inputs: a sweep over a link
mass recompiles nothing), with the file's values as defaults — ``True`` for all, or some of
``"mass"`` (``m_<link>``, kg, positive), ``"com"`` (``cx_<link>``, ``cy_…``, ``cz_…``, m, in
the link frame), ``"inertia"`` (``Ixx_<link>``, ``Ixy_…``, ``Ixz_…``, ``Iyy_…``, ``Iyz_…``,
``Izz_…``, kg m², about the centre of mass in the link frame) and ``"length"`` (``x_<joint>``,
``y_…``, ``z_…``, m: the joint origin in its parent link's frame). An entry that is zero in the
file stays an exact zero (it shapes the compiled code: making it nonzero is a new structure),
and characters other than letters, digits and ``_`` in a name become ``_``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ModelError
from .tree import Joint

_SUPPORTED = ("revolute", "continuous", "prismatic", "fixed")
PARAMETER_KINDS = ("mass", "com", "inertia", "length")


class _Params:
    """The file's numbers, as named model parameters for the chosen kinds (zeros stay zeros)."""

    def __init__(self, model: Any, parameters: bool | Collection[str]) -> None:
        kinds = set(PARAMETER_KINDS) if parameters is True else set(parameters or ())
        bad = kinds - set(PARAMETER_KINDS)
        if bad:
            raise ModelError(f"from_urdf: unknown parameter kind(s) {', '.join(sorted(bad))} "
                             f"(known: {', '.join(PARAMETER_KINDS)})")
        self.model, self.kinds = model, kinds

    def _one(self, kind: str, name: str, value: float, unit: str, doc: str) -> Any:
        if kind not in self.kinds or value == 0.0:
            return float(value)
        from .domain import POSITIVE

        name = re.sub(r"\W", "_", name)
        return self.model.parameter(name, float(value), doc=doc, unit=unit,
                                    domain=POSITIVE if kind == "mass" else None)

    def inertial(self, link: str, mass: float, com: np.ndarray, inertia: np.ndarray) -> tuple[Any, Any, Any]:
        m = self._one("mass", f"m_{link}", mass, "kg", f"mass of link {link}")
        c = tuple(self._one("com", f"c{a}_{link}", v, "m", f"centre of mass of link {link}, {a}")
                  for a, v in zip("xyz", com))
        ax = "xyz"
        entries = {(i, j): self._one("inertia", f"I{ax[i]}{ax[j]}_{link}", inertia[i, j], "kg*m^2",
                                     f"inertia of link {link} about its centre of mass, {ax[i]}{ax[j]}")
                   for i in range(3) for j in range(i, 3)}
        I = [[entries[min(i, j), max(i, j)] for j in range(3)] for i in range(3)]
        return m, c, I

    def offset(self, joint: str, xyz: np.ndarray) -> tuple[Any, ...]:
        return tuple(self._one("length", f"{a}_{joint}", v, "m", f"origin of joint {joint}, {a}")
                     for a, v in zip("xyz", xyz))


def _read(path: Path) -> tuple[Any, Any]:
    """The parsed URDF and the root element of the strict parse (:func:`_check_document`)."""
    try:
        import yourdfpy
    except ImportError as e:  # pragma: no cover - a declared dependency
        raise ModelError("URDF import needs the 'yourdfpy' package: pip install 'amble[urdf]'") from e
    root = _check_document(path)
    try:
        return yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False,
                                  build_collision_scene_graph=False, load_collision_meshes=False), root
    except Exception as e:  # the parser's own errors (malformed XML, missing attributes)
        raise ModelError(f"URDF {path.name}: cannot be read: {e}") from e


def _check_document(path: Path) -> Any:
    """:class:`ModelError` for a file that is not well-formed XML (a truncated file, a NUL byte),
    is not a robot (another root element, no link, no name) or whose elements contradict each
    other: two links or two joints of one name, a ``<mimic>`` naming no joint of the file.

    The parser falls back to a recovering parse when the strict one fails, which reads a file
    cut short or holding a NUL byte as if the missing or unreadable elements had never been
    there (a robot with fewer links and no complaint); it also keeps one of two links of the same
    name. So the file is parsed strictly here first; its root element is returned."""
    import xml.etree.ElementTree as ET

    try:
        data = path.read_bytes()
    except OSError as e:
        raise ModelError(f"URDF {path.name}: cannot be read ({e.strerror or e})") from None
    nul = data.find(b"\0")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        raise ModelError(f"URDF {path.name}: NUL byte at line {line} (byte {nul}): not a text file")
    try:
        root = ET.fromstring(data)
    except ET.ParseError as e:
        line, col = e.position
        raise ModelError(f"URDF {path.name}: not well-formed XML at line {line}, column {col + 1} "
                         f"({str(e).split(':')[0]}): is the file complete?") from None
    if root.tag != "robot":
        raise ModelError(f"URDF {path.name}: the root element is <{root.tag}>, not <robot>")
    if not root.findall("link"):
        raise ModelError(f"URDF {path.name}: the <robot> declares no link (an empty description)")
    if not root.get("name"):
        raise ModelError(f"URDF {path.name}: the <robot> element has no name attribute, which URDF requires")
    for kind in ("link", "joint"):
        seen: set[str] = set()
        for el in root.findall(kind):
            name = el.get("name")
            if name in seen:
                raise ModelError(f"URDF {path.name}: two {kind}s named {name!r}")
            seen.add(name)
    joints = {el.get("name") for el in root.findall("joint")}
    for el in root.findall("joint"):
        for mimic in el.findall("mimic"):
            target = mimic.get("joint")
            if target not in joints:
                raise ModelError(f"URDF joint {el.get('name')!r}: <mimic> names joint {target!r}, "
                                 "which the file does not declare")
    return root


#: relative tolerance of the inertia checks: the rounding of numbers written to a file
_TOL = 1e-9
#: a length (m) below which a link's extent does not matter: ``mass · _LENGTH²`` is the scale of
#: the inertia checks for a point mass, whose written inertia is zero or rounding (1e-35 kg m²)
_LENGTH = 1e-3


def _check_moments(name: str, moments: np.ndarray, scale: float) -> None:
    """The principal moments of inertia of a rigid body: none negative and each at most the sum of
    the other two (``I_x + I_y = ∫ (x² + y² + 2 z²) dm ≥ I_z``), both up to ``_TOL · scale`` so that
    an inertia rounded when written (a thin rod, a flat plate, a point mass) still passes."""
    tol = _TOL * scale
    if moments.min() < -tol:
        raise ModelError(f"URDF link {name!r}: inertia tensor has a negative principal moment "
                         f"(eigenvalues {', '.join(f'{v:g}' for v in moments)}): not positive semi-definite")
    largest, total = float(moments.max()), float(moments.sum())
    if largest > total - largest + tol:
        raise ModelError(f"URDF link {name!r}: principal moments of inertia "
                         f"{', '.join(f'{v:g}' for v in moments)} violate the triangle inequality "
                         "(each must be at most the sum of the other two): no rigid body has them")


def _check_inertial(link: Any, moves: bool = True) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre of mass (link frame) and inertia about it (link axes) of a link; ``moves``:
    False for a base fixed to the world, whose inertial enters no equation and is only checked to
    be numbers (a file may give it a placeholder, ANYmal's ``diag(0, 0, 3e-6)`` of 1 mg).

    Every physical inertia passes: positive semi-definite (a thin rod has a zero moment), a point
    mass (zero inertia), a massless frame; eigenvalues negative by rounding only (``-2e-22`` next
    to ``3e-6``) are accepted, relative to the larger of the tensor's own size and ``mass · (1 mm)²``.
    The file's numbers are kept as written (Pinocchio's too: the rounding is far below that of M)."""
    ine = link.inertial
    mass = float(ine.mass) if ine.mass is not None else 0.0
    if not math.isfinite(mass):
        raise ModelError(f"URDF link {link.name!r}: mass {mass:g} is not finite")
    if not mass >= 0.0:
        raise ModelError(f"URDF link {link.name!r}: negative mass {mass:g}")
    T = np.eye(4) if ine.origin is None else np.asarray(ine.origin, dtype=float)
    I = np.zeros((3, 3)) if ine.inertia is None else np.asarray(ine.inertia, dtype=float)
    if not np.isfinite(I).all() or not np.isfinite(T).all():
        raise ModelError(f"URDF link {link.name!r}: inertial has a non-finite number")
    if not np.allclose(I, I.T, rtol=0, atol=1e-12 * max(1.0, np.abs(I).max())):
        raise ModelError(f"URDF link {link.name!r}: inertia tensor is not symmetric")
    if moves:
        ev = np.linalg.eigvalsh(I)
        _check_moments(link.name, ev, max(float(np.abs(ev).sum()), mass * _LENGTH**2))
    Rc = T[:3, :3]
    return mass, T[:3, 3].copy(), Rc @ I @ Rc.T


def _tree_order(robot: Any, base: str | None, path: Path) -> tuple[dict[str, Any], str, list[tuple]]:
    """The URDF's links by name, the base link and the links in breadth-first order from it, each
    as ``(link, parent link or None at the base, joint, forward)`` (``forward``: the joint is
    traversed from its parent to its child). Unsupported joints, unknown links, loops, several
    roots and links not connected to the base are :class:`ModelError`."""
    links = {lk.name: lk for lk in robot.links}
    joints = list(robot.joints)
    for j in joints:
        if j.type not in _SUPPORTED:
            kind = "unsupported" if j.type in ("floating", "planar") else "unknown"
            raise ModelError(f"URDF joint {j.name!r}: {kind} joint type {j.type!r} "
                             f"(supported: {', '.join(_SUPPORTED)})")
        for end in (j.parent, j.child):
            if end not in links:
                raise ModelError(f"URDF joint {j.name!r}: unknown link {end!r}")
    parents: dict[str, str] = {}
    for j in joints:
        if j.child in parents:
            raise ModelError(f"URDF link {j.child!r} has two parent joints ({parents[j.child]!r}, {j.name!r}): "
                             "a kinematic loop")
        parents[j.child] = j.name
    roots = [lk for lk in links if lk not in parents]
    if len(roots) != 1:
        raise ModelError(f"URDF {path.name}: expected one root link, found {len(roots)}"
                         + (f" ({', '.join(roots)})" if roots else " (the joints form a loop)"))
    base = base or roots[0]
    if base not in links:
        raise ModelError(f"URDF {path.name}: base link {base!r} is not a link "
                         f"(links: {', '.join(links)})")

    adjacent: dict[str, list[tuple[Any, bool]]] = {lk: [] for lk in links}
    for j in joints:
        adjacent[j.parent].append((j, True))
        adjacent[j.child].append((j, False))
    order: list[tuple[str, str | None, Any, bool]] = []   # (link, parent link, joint, forward)
    seen = {base}
    stack = [base]
    while stack:
        lk = stack.pop(0)
        for j, forward in adjacent[lk]:
            other = j.child if forward else j.parent
            if other in seen:
                continue
            seen.add(other)
            order.append((other, None if lk == base else lk, j, forward))
            stack.append(other)
    missing = [lk for lk in links if lk not in seen]
    if missing:
        raise ModelError(f"URDF {path.name}: links not connected to {base!r}: {', '.join(missing)}")
    return links, base, order


def _mimics(robot: Any) -> dict[str, tuple[str, float, float]]:
    """Each moving joint with a ``<mimic>`` as ``(joint it follows, multiplier, offset)``, a chain
    (a mimic of a mimic) resolved to the joint at its end: ``q = k₁ (k₂ q_c + c₂) + c₁``. A fixed
    joint's ``<mimic>`` moves nothing and is dropped (a reduced file keeps the tag); a mimic of a
    fixed joint, or a loop of mimics, is :class:`ModelError`."""
    joints = {j.name: j for j in robot.joints}
    direct = {j.name: j.mimic for j in robot.joints if j.mimic is not None and j.type != "fixed"}
    out: dict[str, tuple[str, float, float]] = {}
    for name in direct:
        k, c, cur, seen = 1.0, 0.0, name, [name]
        while cur in direct:
            mm = direct[cur]
            kk = 1.0 if mm.multiplier is None else float(mm.multiplier)
            cc = 0.0 if mm.offset is None else float(mm.offset)
            k, c, cur = k * kk, k * cc + c, mm.joint
            if cur in seen:
                raise ModelError(f"URDF joint {name!r}: <mimic> joints follow each other in a loop "
                                 f"({' -> '.join(seen + [cur])})")
            seen.append(cur)
        if joints[cur].type == "fixed":
            raise ModelError(f"URDF joint {name!r}: <mimic> follows joint {cur!r}, which is fixed")
        out[name] = (cur, k, c)
    return out


def _mimic_order(order: list[tuple], mimics: Mapping[str, tuple[str, float, float]]) -> list[tuple]:
    """``order`` (links from the base, each after its parent) with every mimic joint's link also
    after the link of the joint it follows (whose coordinate it is made of); otherwise unchanged."""
    placed: set[str] = set()
    declared: set[str] = set()
    out: list[tuple] = []
    pending = list(order)
    while pending:
        rest = []
        for item in pending:
            lk, parent, j, _ = item
            if (parent is None or parent in placed) and (j.name not in mimics or mimics[j.name][0] in declared):
                out.append(item)
                placed.add(lk)
                declared.add(j.name)
            else:
                rest.append(item)
        if len(rest) == len(pending):
            j = next(it[2] for it in rest if it[2].name in mimics)
            raise ModelError(f"URDF joint {j.name!r}: <mimic> follows joint {mimics[j.name][0]!r}, which only "
                             "moves links below it (seen from the base): a mimic must follow a joint that is not "
                             "its descendant")
        pending = rest
    return out


def _joint(j: Any, forward: bool, par: _Params, mimics: Mapping[str, tuple[str, float, float]]) -> Joint:
    """The tree joint of the URDF joint ``j`` traversed from its parent (``forward``) or back."""
    T = np.eye(4) if j.origin is None else np.asarray(j.origin, dtype=float)
    xyz = np.asarray(par.offset(j.name, T[:3, 3]), dtype=object)
    axis = np.asarray(j.axis if j.axis is not None else (1.0, 0.0, 0.0), dtype=float)
    lower = upper = None
    if j.type in ("revolute", "prismatic") and j.limit is not None:
        lower, upper = j.limit.lower, j.limit.upper
    ref, k, c = mimics.get(j.name, (None, 1.0, 0.0))
    tie = dict(mimic=ref, multiplier=k, offset=c)
    if forward:
        return Joint(j.type, axis=tuple(axis), xyz=tuple(xyz), rotation=T[:3, :3], lower=lower, upper=upper, **tie)
    # traversed from child to parent: T⁻¹ = J(q)⁻¹ T_o⁻¹
    Rt = T[:3, :3].T
    post = [-v for v in _rotate(Rt, xyz)]
    return Joint(j.type, axis=tuple(-axis), post_xyz=tuple(post), post_rotation=Rt, lower=lower, upper=upper, **tie)


def _rotate(R: np.ndarray, v: Any) -> list:
    """``R v`` for a numeric ``R`` and entries that may be parameters; exact zeros stay zeros."""
    return [sum((R[i, k] * v[k] for k in range(3) if R[i, k] != 0 and v[k] != 0), 0.0) for i in range(3)]


def _add(a: Any, b: Any) -> list:
    return [x + y if x != 0 and y != 0 else (x if y == 0 else y) for x, y in zip(a, b)]


def _rotation_of(joint: Joint) -> np.ndarray:
    from .tree import rpy_matrix

    return np.asarray(joint.rotation, dtype=float) if joint.rotation is not None else rpy_matrix(joint.rpy)


def _massless(mass: Any, inertia: Any) -> bool:
    """Zero mass and zero inertia, as numbers (a parameter is never zero: zeros stay numbers)."""
    return isinstance(mass, float) and mass == 0.0 and all(
        isinstance(v, float) and v == 0.0 for row in inertia for v in row)


def _joint_dynamics(tree: Any, order: list[tuple], path: Path, transmissions: int) -> None:
    """Each moving joint's ``<dynamics damping="d">`` as the generalised force ``−d θ̇`` on its
    angle (or travel) ``θ``: by virtual work ``−d k² ȧ`` on the coordinate ``a`` of a mimic joint
    ``θ = k a + c``. Coulomb ``friction`` (a set-valued force at rest) and ``<transmission>``
    elements are ignored with a warning."""
    import warnings

    damped = []
    rubbing = []
    for lk, _, j, _ in order:
        dyn = j.dynamics
        if j.type == "fixed" or dyn is None or lk not in tree._by_name:
            continue
        b = tree[lk]
        # the parser keeps the attributes as text
        d = _number(dyn.damping, f"URDF joint {j.name!r}: damping")
        f = _number(dyn.friction, f"URDF joint {j.name!r}: friction")
        if d:
            damped.append((b, d))
        if f:
            rubbing.append(j.name)
    tree.joint_damping(damped)
    ignored = []
    if rubbing:
        ignored.append(f"joint friction ({', '.join(rubbing[:4])}{', …' if len(rubbing) > 4 else ''})")
    if transmissions:
        ignored.append(f"{transmissions} <transmission> element(s)")
    if ignored:
        warnings.warn(f"URDF {path.name}: ignored: {'; '.join(ignored)}", stacklevel=4)


def _number(text: Any, what: str) -> float:
    """A non-negative finite number of the file (``None``: 0)."""
    if text is None:
        return 0.0
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise ModelError(f"{what} {text!r} is not a number") from None
    if not (math.isfinite(v) and v >= 0.0):
        raise ModelError(f"{what} {v:g} must be finite and non-negative")
    return v


def build_model(cls: type, path: Any, base: str | None = None, contact_points: Mapping | None = None,
                name: str | None = None, allow_massless: bool = False, gravity: float = 9.81,
                base_joint: Joint | None = None, base_coordinate: str = "base",
                parameters: bool | Collection[str] = False, pivot: str | None = None) -> Any:
    """A model (of class ``cls``, a :class:`~amble.modelling.model.Model`) of the URDF at ``path``
    with ``base`` fixed to the world (default: the URDF's root link), or attached to it by
    ``base_joint`` (e.g. a revolute pivot at a point foot) with the coordinate ``base_coordinate``;
    ``parameters``: which numbers become named model parameters (module docstring); ``pivot``:
    a contact point on the base link where ``base_joint`` is centred (a point foot pivoting at
    its sole) instead of the link's origin."""
    path = Path(path)
    if pivot is not None:
        spec = (contact_points or {}).get(pivot)
        if base_joint is None or spec is None or spec[0] != (base or spec[0]):
            raise ModelError(f"pivot {pivot!r}: give a base_joint and a contact point of that name on the base link")
        if base_joint.post_xyz is not None:
            raise ModelError(f"pivot {pivot!r}: the base joint has an offset after its motion already")
        base_joint = dataclasses.replace(base_joint, post_xyz=tuple(-float(v) for v in spec[1]))
    urdf, root = _read(path)
    robot = urdf.robot
    links, base, order = _tree_order(robot, base, path)
    mimics = _mimics(robot)
    order = _mimic_order(order, mimics)
    for lk in links.values():  # every inertial is checked before the tree is built, the base's too
        if lk.inertial is not None:
            _check_inertial(lk, moves=lk.name != base or base_joint is not None)
    model = cls(name or robot.name or path.stem, dims=3)
    model.gravity(gravity)
    par = _Params(model, parameters)
    tree = model.rigid_tree()
    top = None
    if base_joint is not None:
        link = links[base]
        mass, com, inertia = (_check_inertial(link) if link.inertial is not None
                              else (0.0, np.zeros(3), np.zeros((3, 3))))
        mass, com, inertia = par.inertial(base, mass, com, inertia)
        tree.body(base, joint=base_joint, mass=mass, com=com, inertia=inertia, coordinate=base_coordinate)
        top = base
    # a massless link on a fixed joint is a frame of the body it hangs from (as Pinocchio merges
    # fixed joints): no body, a named point at its origin, and its children placed through it
    frames: dict[str, tuple[str, np.ndarray, np.ndarray]] = {}   # link → (body, rotation, origin)
    for lk, parent, j, forward in order:
        parent = parent or top
        link = links[lk]
        if link.inertial is None:
            mass, com, inertia = 0.0, np.zeros(3), np.zeros((3, 3))
        else:
            mass, com, inertia = _check_inertial(link)
        if j.type != "fixed" and not allow_massless and mass == 0.0 and not np.any(inertia):
            # a joint moving nothing has no inertia: M is singular unless links below carry mass
            what = "no inertial" if link.inertial is None else "an inertial of zero mass and inertia"
            raise ModelError(f"URDF link {lk!r} is moved by joint {j.name!r} but has {what} "
                             "(give it one, or load with allow_massless=True)")
        mass, com, inertia = par.inertial(lk, mass, com, inertia)
        joint = _joint(j, forward, par, mimics)
        if parent in frames:
            parent, Rf, pf = frames[parent]
            joint = dataclasses.replace(joint, xyz=tuple(_add(pf, _rotate(Rf, joint.xyz))),
                                        rotation=Rf @ _rotation_of(joint))
        if j.type == "fixed" and parent is not None and _massless(mass, inertia):
            Rp = _rotation_of(joint)
            origin = _add(joint.xyz, _rotate(Rp, joint.post_xyz or (0, 0, 0)))
            post = np.eye(3) if joint.post_rotation is None else np.asarray(joint.post_rotation, dtype=float)
            frames[lk] = (parent, Rp @ post, origin)
            tree.point(lk, parent, origin)
            model.link(parent, lk)
            continue
        tree.body(lk, parent=parent, joint=joint, mass=mass, com=com, inertia=inertia,
                  coordinate=j.name)
    _joint_dynamics(tree, order, path, len(root.findall("transmission")))
    tree.file = path
    tree.link_frames = dict(frames)
    if base_joint is None:   # the base link is the world frame
        tree.link_frames[base] = (None, np.eye(3), (0.0, 0.0, 0.0))
    for pname, spec in (contact_points or {}).items():
        try:
            lk, at = spec
        except (TypeError, ValueError):
            raise ModelError(f"contact point {pname!r}: give (link, (x, y, z)), got {spec!r}") from None
        if lk == base and base_joint is None:
            raise ModelError(f"contact point {pname!r} is on the base link {base!r}, which does not move")
        if lk in frames:
            lk, Rf, pf = frames[lk]
            at = _add(pf, _rotate(Rf, at))
        tree.point(pname, lk, at)
    return model
