"""A point-foot walker from a robot file in one call: each foot in turn the base of the tree.

:func:`point_foot_walker` loads the URDF once per stance foot, rooted at that foot and attached to
the ground by a pivot at the foot's contact point (``Joint("spherical")``: coordinates
``stance_yaw``, ``stance_pitch``, ``stance_roll``; or a revolute joint about a given axis,
coordinate ``stance``, for a walker kept in a plane), actuates every other moving joint and
joins the two modes with :func:`~amble.modelling.stance_feet.stance_feet_walker` (a derived
plastic impact of the striking foot's contact point, the frame moved there, the new base's
angles read from the old pose).

Virtual constraints of hybrid zero dynamics (:class:`VirtualOutputs`) may be declared on both
modes: the outputs are the joint angles ordered *stance leg, swing leg, other joints*, the legs
each from the hip down, and in the second mode every angle multiplied by the sign that maps a
joint onto its mirror image across the robot's sagittal plane (below), so that one set of
Bézier coefficients ``alpha_<i>_<k>`` — parameters shared by the two modes — describes a gait
whose right step is the mirror image of its left step.

**The legs and their mirror signs.** A leg is the chain of moving joints from the two feet's
lowest common ancestor link down to a foot. Reflecting the robot across the ``x–z`` plane of that
link (URDF's convention: ``x`` forward, ``y`` to the left, ``z`` up) maps a rotation by ``θ``
about an axis ``a`` to a rotation by ``θ`` about ``−S a`` (``S = diag(1, −1, 1)``; a reflection
reverses the sense of rotation). So the ``i``-th joint of one leg, axis ``a_L`` (in the common
link's frame, at the zero pose), mirrors the ``i``-th of the other, axis ``a_R``, with sign ``+1``
if ``a_R = −S a_L`` (a pitch axis ``y`` on both legs) and ``−1`` if ``a_R = S a_L`` (a roll axis
``x`` on both legs: Bolt's ``FL_HAA`` and ``FR_HAA``, whose standing pose is ``−0.3`` and
``+0.3``). A joint on neither leg mirrors itself: ``+1`` for an axis normal to the plane, ``−1``
for one in it. Legs that are not mirror images (another number of joints, an axis neither
way) are a :class:`~amble.errors.ModelError` unless ``mirror=False`` (every sign ``+1``).

**The phase.** ``"hip"`` (default): the hip point's distance ahead of the stance foot along the
slope (m; the stance foot is the origin of every step's frame), which grows monotonically while
the body vaults over the stance leg, whatever the joints' sign conventions, and is the same in
both modes for mirrored poses. A callable ``phase(model) → expression of q`` gives another one
(e.g. a stance-leg angle as a sum of coordinates, affine in ``q``).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from ..errors import ModelError
from .bodies import Joint
from .contact import distance_along_slope
from .dag import dag_subs
from .model import Model
from .sparse_algebra import rpy_matrix
from .stance_feet import stance_feet_walker
from .walker import Walker

#: the reflection across the sagittal plane x–z of the legs' common link
_S = np.diag([1.0, -1.0, 1.0])
#: the pivot's coordinates (revolute; spherical), not actuated
_PIVOT = frozenset({"stance", "stance_yaw", "stance_pitch", "stance_roll"})


@dataclass(frozen=True)
class VirtualOutputs:
    """Virtual constraints to declare on a point-foot walker's modes (module docstring).

    ``alpha``: one row of Bézier coefficients (rad) per output, in the order of the outputs
    (stance-leg joints, swing-leg joints, other joints); ``None``: ``degree + 1`` zeros per row
    (every joint held at zero until a designed gait's coefficients are set as parameter values
    ``alpha_<i>_<k>``). ``phase``: ``"hip"`` or a callable ``model → expression`` (see the
    module docstring); ``phase_range``: its values ``(θ⁺, θ⁻)`` just after and at a footfall
    (m for ``"hip"``). ``epsilon`` (s), ``kp``, ``kd``: the output dynamics
    ``ÿ = −kd ẏ/ε − kp y/ε²``. ``mirror``: the second mode's outputs are mirror images of the
    first's (module docstring); ``False``: the same joints, unsigned. ``shared``: one set of
    coefficients and phase range for both modes (a gait whose steps are mirror images); ``False``:
    each mode its own, ``<mode>_alpha_<i>_<k>``, ``<mode>_phase_start``, ``<mode>_phase_end`` — a
    robot whose legs are mirror images only to some digits (Bolt's centres of mass differ by
    1e-5 m from leg to leg) has no gait whose steps are exact mirror images."""

    degree: int = 4
    alpha: Sequence[Sequence[float]] | None = None
    phase: str | Callable[[Model], Any] = "hip"
    phase_range: tuple[float, float] = (-0.05, 0.05)
    epsilon: float = 0.1
    kp: float = 1.0
    kd: float = 2.0
    mirror: bool = True
    shared: bool = True


@dataclass
class _Urdf:
    """What the walker needs of the file's tree: joints by child link, links, children."""

    links: list[str]
    by_child: dict[str, ET.Element]
    children: dict[str, list[str]]
    root: str

    @classmethod
    def read(cls, path: Path) -> _Urdf:
        try:
            doc = ET.parse(path).getroot()
        except (OSError, ET.ParseError) as e:
            raise ModelError(f"robot file {path.name}: cannot be read ({e})") from None
        links = [el.get("name") for el in doc.findall("link")]
        by_child = {el.find("child").get("link"): el for el in doc.findall("joint")
                    if el.find("child") is not None and el.find("parent") is not None}
        children: dict[str, list[str]] = {lk: [] for lk in links}
        for child, el in by_child.items():
            children.setdefault(el.find("parent").get("link"), []).append(child)
        roots = [lk for lk in links if lk not in by_child]
        # from_urdf says what is wrong with a file of several roots; the walker needs one
        return cls(links, by_child, children, roots[0] if len(roots) == 1 else "")

    def path_to(self, link: str) -> list[str]:
        """The links from the root down to ``link``."""
        out = [link]
        while out[-1] in self.by_child:
            out.append(self.by_child[out[-1]].find("parent").get("link"))
        return out[::-1]

    def joint_frame(self, el: ET.Element) -> tuple[np.ndarray, np.ndarray]:
        """A joint's origin rotation and its unit axis in its parent link's frame."""
        org = el.find("origin")
        rpy = [float(v) for v in (org.get("rpy", "0 0 0") if org is not None else "0 0 0").split()]
        ax = el.find("axis")
        a = np.array([float(v) for v in (ax.get("xyz", "1 0 0") if ax is not None else "1 0 0").split()])
        R = np.array(rpy_matrix(rpy), dtype=float)
        return R, R @ (a / np.linalg.norm(a))

    def effort(self, joint: str) -> float | None:
        for el in self.by_child.values():
            if el.get("name") == joint:
                lim = el.find("limit")
                try:
                    v = float(lim.get("effort")) if lim is not None and lim.get("effort") else None
                except ValueError:
                    raise ModelError(f"URDF joint {joint!r}: effort {lim.get('effort')!r} is not a number") from None
                return v if v is not None and v > 0 and math.isfinite(v) else None
        return None


def _check_feet(urdf: _Urdf, path: Path, feet: Mapping[str, Any], hip: str | None) -> dict[str, tuple]:
    """``feet`` as ``{mode: (link, (x, y, z))}``, each a leaf link of the file, two different ones."""
    if not isinstance(feet, Mapping) or len(feet) != 2:
        raise ModelError(f"feet: give two stance feet as {{mode: (link, (x, y, z))}}, got {feet!r}")
    out = {}
    for mode, spec in feet.items():
        try:
            link, at = spec
            at = tuple(float(v) for v in at)
        except (TypeError, ValueError):
            raise ModelError(f"foot {mode!r}: give (link, (x, y, z)) — the contact point in the link's frame, m; "
                             f"got {spec!r}") from None
        if len(at) != 3 or not all(math.isfinite(v) for v in at):
            raise ModelError(f"foot {mode!r}: the contact point needs three finite coordinates, got {at}")
        if link not in urdf.links:
            raise ModelError(f"foot {mode!r}: {path.name} has no link {link!r}")
        if urdf.children.get(link):
            raise ModelError(f"foot {mode!r}: link {link!r} is not a leaf of the tree (it carries "
                             f"{', '.join(urdf.children[link])}); a point foot ends a leg")
        if link in urdf.links and f"{mode}_sole" in urdf.links:
            raise ModelError(f"foot {mode!r}: the contact point's name {mode}_sole is a link of the file")
        out[str(mode)] = (link, at)
    (a, (la, _)), (b, (lb, _)) = out.items()
    if la == lb:
        raise ModelError(f"feet {a!r} and {b!r} are the same link {la!r}")
    if hip is not None and hip not in urdf.links:
        raise ModelError(f"hip: {path.name} has no link {hip!r}")
    if hip in (la, lb):
        raise ModelError(f"hip {hip!r} is a foot")
    return out


def _legs(urdf: _Urdf, feet: Sequence[str], coords: set[str]) -> tuple[str, list[list[str]]]:
    """The feet's lowest common ancestor link and each leg's joints with a coordinate, from it down."""
    paths = [urdf.path_to(f) for f in feet]
    k = 0
    while k < min(map(len, paths)) and paths[0][k] == paths[1][k]:
        k += 1
    common = paths[0][k - 1]
    legs = [[urdf.by_child[lk].get("name") for lk in p[k:] if urdf.by_child[lk].get("name") in coords]
            for p in paths]
    return common, legs


def _axes(urdf: _Urdf, common: str) -> dict[str, np.ndarray]:
    """Each joint's axis in ``common``'s frame at the zero pose, for the joints below ``common``."""
    out: dict[str, np.ndarray] = {}
    rot = {common: np.eye(3)}
    stack = [common]
    while stack:
        lk = stack.pop()
        for child in urdf.children.get(lk, []):
            el = urdf.by_child[child]
            R, a = urdf.joint_frame(el)
            out[el.get("name")] = rot[lk] @ a
            rot[child] = rot[lk] @ R
            stack.append(child)
    return out


def _mirror_signs(urdf: _Urdf, common: str, legs: list[list[str]], others: list[str]) -> dict[str, float]:
    """The sign of each joint's angle in its mirror image (module docstring)."""
    axes = _axes(urdf, common)
    left, right = legs
    if len(left) != len(right):
        raise ModelError(f"virtual constraints: the legs have {len(left)} and {len(right)} moving joints, "
                         "not mirror images (give VirtualOutputs(mirror=False))")
    signs: dict[str, float] = {}
    for a, b in zip(left, right):
        for s in (1.0, -1.0):
            if np.allclose(axes[b], -s * (_S @ axes[a]), atol=1e-9):
                signs[a] = signs[b] = s
                break
        else:
            raise ModelError(f"virtual constraints: joints {a!r} and {b!r} are not mirror images across the "
                             f"x-z plane of {common!r} (axes {axes[a].round(6)}, {axes[b].round(6)}); give "
                             "VirtualOutputs(mirror=False)")
    for j in others:
        a = axes.get(j)
        if a is None:  # above the common link: its axis in that link's frame is not at hand
            raise ModelError(f"virtual constraints: joint {j!r} is above the legs' common link {common!r}; "
                             "give VirtualOutputs(mirror=False)")
        for s in (1.0, -1.0):
            if np.allclose(a, -s * (_S @ a), atol=1e-9):
                signs[j] = s
                break
        else:
            raise ModelError(f"virtual constraints: joint {j!r} is on neither leg and its axis {a.round(6)} is "
                             f"neither in nor normal to the x-z plane of {common!r}; give VirtualOutputs(mirror=False)")
    return signs


def _linear_hip(m: Model, hip: str, slope: float) -> sp.Expr:
    """The hip's distance ahead of the stance foot along the slope, linearised at the zero pose:
    ``Σ ∂d/∂qᵢ(0) qᵢ`` (m). Affine in ``q``: the input–output law then differentiates constants
    (the exact distance, a function of every joint of the stance leg, makes the law's code some
    thirty times larger: 48 MB of C for Bolt)."""
    d = distance_along_slope(m, hip, slope)
    at = {q: sp.Float(0.0) for q in m.q}
    at.update({p: sp.Float(float(v)) for p, v in m.params.items()})
    grad = m.jacobian(sp.Matrix([d]))
    coeffs = [float(e) for e in dag_subs(grad, at)]
    return sum((sp.Float(round(c, 15)) * q for c, q in zip(coeffs, m.q) if abs(c) > 1e-15), sp.Integer(0))


def _others(m: Model, legs: Any) -> list[str]:
    """The actuated joints of ``m`` on neither leg, in the model's order."""
    on_legs = {j for leg in legs for j in leg}
    return [j for j in (str(q) for q in m.q) if j not in _PIVOT and j not in on_legs]


def _declare_outputs(modes: Mapping[str, Model], legs: dict[str, list[str]], signs: dict[str, float],
                     spec: VirtualOutputs, hip: str, slope: float) -> None:
    first, second = modes
    others = _others(modes[first], legs.values())
    n = len(legs[first]) + len(legs[second]) + len(others)
    rows = list(spec.alpha) if spec.alpha is not None else [[0.0] * (spec.degree + 1)] * n
    for mode, (stance, swing) in ((first, (first, second)), (second, (second, first))):
        m = modes[mode]
        q = {str(s): s for s in m.q}
        order = legs[stance] + legs[swing] + others
        sign = (lambda j: 1.0) if mode == first else (lambda j: signs.get(j, 1.0))
        outputs = [q[j] if sign(j) > 0 else -q[j] for j in order]
        if spec.phase == "hip":
            phase = _linear_hip(m, hip, slope)
        elif callable(spec.phase):
            phase = spec.phase(m)
        else:
            raise ModelError(f"virtual constraints: phase must be 'hip' or a callable model -> expression, "
                             f"got {spec.phase!r}")
        m.virtual_constraints(outputs, phase, rows, spec.phase_range, epsilon=spec.epsilon, kp=spec.kp,
                              kd=spec.kd, prefix="" if spec.shared else f"{mode}_")


def point_foot_walker(path: str | Path, feet: Mapping[str, tuple[str, Sequence[float]]], hip: str | None = None,
                      pivot: str | Sequence[float] = "spherical", slope: float = 0.0, name: str | None = None,
                      max_step_time: float = 2.0, virtual: VirtualOutputs | None = None,
                      parameters: bool | Sequence[str] = False) -> Walker:
    """A walker of two stance modes from the URDF at ``path`` (module docstring).

    ``feet``: ``{mode: (link, (x, y, z))}`` — per mode (e.g. ``"left"``, ``"right"``; the first is
    the default start's), the stance foot's link, a leaf of the tree, and its contact point in
    that link's frame (m), a model point named ``<mode>_sole`` in both modes. ``hip``: the link
    whose centre of mass is the walker's hip (a fall ends a run when it reaches the ground);
    default the file's root link, the floating base of the robot. ``pivot``: ``"spherical"`` (3D:
    ``stance_yaw``, ``stance_pitch``, ``stance_roll``, rad, the foot's rotation
    ``Rz(yaw) Ry(pitch) Rx(roll)``) or a unit axis ``(x, y, z)`` of a revolute pivot (coordinate
    ``stance``, rad; a walker kept in a plane). Every other moving joint is actuated: input
    ``u_<joint>`` (N·m, or N for a prismatic joint), bounded by the joint's URDF ``effort`` where it
    gives one; the inputs are zero until a law is given (``walker.modes[mode].control``) or
    ``virtual`` declares virtual constraints. ``slope`` (rad): the ground descends along ``+x``.
    ``parameters``: the file's numbers that become model parameters (:meth:`Model.from_urdf`)."""
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"robot file {str(path)!r} does not exist")
    urdf = _Urdf.read(path)
    spec = _check_feet(urdf, path, feet, hip)
    hip = hip or urdf.root
    if isinstance(pivot, str):
        if pivot != "spherical":
            raise ModelError(f"pivot must be 'spherical' or an axis (x, y, z), got {pivot!r}")
        base_joint = Joint("spherical")
    else:
        try:
            axis = np.asarray([float(v) for v in pivot])
        except (TypeError, ValueError):
            raise ModelError(f"pivot must be 'spherical' or an axis (x, y, z), got {pivot!r}") from None
        if axis.shape != (3,) or not np.isfinite(axis).all() or np.linalg.norm(axis) == 0:
            raise ModelError(f"pivot axis must be three finite numbers, not all zero; got {tuple(pivot)}")
        base_joint = Joint("revolute", axis=tuple(axis / np.linalg.norm(axis)))
    soles = {f"{mode}_sole": (link, at) for mode, (link, at) in spec.items()}
    modes: dict[str, Model] = {}
    robot = None
    for mode, (link, _) in spec.items():
        m = Model.from_urdf(path, name=f"{mode}_stance", base=link, base_joint=base_joint,
                            base_coordinate="stance", pivot=f"{mode}_sole", contact_points=soles,
                            allow_massless=True, parameters=parameters)
        robot = robot or m.tree.file.stem
        for q in m.q:
            if str(q) not in _PIVOT:
                m.actuator(f"u_{q}", on=q, limit=urdf.effort(str(q)))
        modes[mode] = m
    w = stance_feet_walker(name or f"{robot}-walk", modes, feet={mode: f"{mode}_sole" for mode in spec},
                           hip=hip, slope=slope, max_step_time=max_step_time,
                           doc=f"{path.name}: point feet {', '.join(f'{k} {v[0]}' for k, v in spec.items())}, "
                               f"{pivot if isinstance(pivot, str) else 'revolute'} pivot")
    if virtual is not None:
        coords = {str(q) for q in modes[next(iter(modes))].q}
        common, legs = _legs(urdf, [link for link, _ in spec.values()], coords)
        others = _others(modes[next(iter(modes))], legs)
        signs = _mirror_signs(urdf, common, legs, others) if virtual.mirror else {}
        _declare_outputs(modes, dict(zip(spec, legs)), signs, virtual, hip, slope)
    return w
