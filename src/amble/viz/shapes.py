"""The shapes of a scene: :class:`Sphere`, :class:`Cylinder`, :class:`Box`, :class:`Ground` and
:class:`Mesh`.

Each shape is a frozen dataclass whose fields declare their own check (see :func:`_field`):
:class:`_Shape` runs the checks, lists the point names a shape needs (:meth:`_Shape.points`)
and writes the scene format (:meth:`_Shape.to_dict`) from the fields, so a new shape only
declares its fields. Units and the scene format are described in :mod:`amble.viz.scene`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, ClassVar

from .errors import SceneError

__all__ = ["Box", "Color", "Cylinder", "Ground", "Mesh", "Shape", "Sphere"]

#: An sRGB colour, three floats in 0..1.
Color = tuple[float, float, float]

#: Decimal places kept in the scene: 1e-5 m / 1e-5 s.
DIGITS = 5

LINK_GREY: Color = (0.62, 0.64, 0.68)
GROUND_COLOR: Color = (0.86, 0.88, 0.91)
# Softened categorical palette, so neighbouring points are told apart at a glance.
PALETTE: tuple[Color, ...] = (
    (0.90, 0.30, 0.24),
    (0.20, 0.47, 0.80),
    (0.30, 0.69, 0.40),
    (0.95, 0.61, 0.13),
    (0.58, 0.40, 0.74),
    (0.10, 0.70, 0.75),
    (0.85, 0.40, 0.65),
    (0.55, 0.45, 0.35),
)


def rounded(x: float) -> float:
    """Round to the scene precision; ``+ 0.0`` turns -0.0 into 0.0."""
    return round(float(x), DIGITS) + 0.0


# ---- checks: (value, field name, class name) -> the normalised value, or SceneError ----------


def check_name(name: object, what: str, owner: str) -> str:
    if not isinstance(name, str) or not name:
        raise SceneError(f"{owner}: {what} must be a non-empty point name, got {name!r}")
    return name


def _three_floats(value: Any, what: str, owner: str, kind: str) -> tuple[float, ...]:
    try:
        v = tuple(float(x) for x in value)
    except TypeError as exc:
        raise SceneError(f"{owner}: {what} must be three floats{kind}, got {value!r}") from exc
    if len(v) != 3:
        raise SceneError(f"{owner}: {what} must be three floats{kind}, got {value!r}")
    return v


def _color(value: Sequence[float], what: str, owner: str) -> Color:
    c = _three_floats(value, what, owner, " in 0..1")
    if not all(0.0 <= v <= 1.0 for v in c):
        raise SceneError(f"{owner}: {what} must be three floats in 0..1, got {value!r}")
    return c  # type: ignore[return-value]


def _opacity(value: float, what: str, owner: str) -> float:
    a = float(value)
    if not 0.0 <= a <= 1.0:
        raise SceneError(f"{owner}: {what} must be in 0..1, got {value!r}")
    return a


def _finite(value: float, what: str, owner: str) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise SceneError(f"{owner}: {what} must be a finite number, got {value!r}")
    return v


def _positive(value: float, what: str, owner: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise SceneError(f"{owner}: {what} must be a positive finite number, got {value!r}")
    return v


def _vec3(value: Sequence[float], what: str, owner: str) -> tuple[float, float, float]:
    v = _three_floats(value, what, owner, "")
    if not all(math.isfinite(x) for x in v):
        raise SceneError(f"{owner}: {what} must be three finite floats, got {value!r}")
    return v  # type: ignore[return-value]


def _size(value: Sequence[float], what: str, owner: str) -> tuple[float, float, float]:
    v = _vec3(value, what, owner)
    for s in v:
        _positive(s, what, owner)
    return v


def _name_pair(value: Sequence[str], what: str, owner: str) -> tuple[str, str]:
    ends = tuple(value)
    if len(ends) != 2:
        raise SceneError(f"{owner}: {what} must be two point names, got {value!r}")
    for name in ends:
        check_name(name, what, owner)
    return ends  # type: ignore[return-value]


def _name_or_vec3(value: Any, what: str, owner: str) -> str | tuple[float, float, float]:
    return check_name(value, what, owner) if isinstance(value, str) else _vec3(value, what, owner)


def _slope(value: float, what: str, owner: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and abs(v) < math.pi / 2):
        raise SceneError(f"{owner}: {what} must be in (-pi/2, pi/2) radians, got {value!r}")
    return v


Check = Callable[[Any, str, str], Any]


def _field(check: Check, default: Any = MISSING, *, point: bool = False) -> Any:
    """A shape field with its check; ``point``: its value names point(s) the shape follows."""
    return field(default=default, metadata={"check": check, "point": point})


def _encode(value: Any) -> Any:
    if isinstance(value, str):
        return value
    if isinstance(value, tuple):
        return [_encode(v) for v in value]
    return rounded(value)


@dataclass(frozen=True)
class _Shape:
    """Checks the fields, lists the needed points and writes the scene format."""

    kind: ClassVar[str]

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for f in fields(self):
            object.__setattr__(self, f.name, f.metadata["check"](getattr(self, f.name), f.name, owner))

    def points(self) -> tuple[str, ...]:
        """Names of the points this shape needs, in field order."""
        out: list[str] = []
        for f in fields(self):
            if f.metadata["point"]:
                v = getattr(self, f.name)
                out.extend([v] if isinstance(v, str) else (x for x in v if isinstance(x, str)))
        return tuple(out)

    def to_dict(self) -> dict[str, Any]:
        """Static properties in the scene format."""
        return {"type": self.kind, **{f.name: _encode(getattr(self, f.name)) for f in fields(self)}}


@dataclass(frozen=True)
class Sphere(_Shape):
    """A ball centred on a named point.

    Attributes:
        at: name of the point the sphere follows.
        radius: radius in metres (> 0).
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible.
    """

    kind: ClassVar[str] = "sphere"
    at: str = _field(check_name, point=True)
    radius: float = _field(_positive)
    color: Color = _field(_color, PALETTE[1])
    opacity: float = _field(_opacity, 1.0)


@dataclass(frozen=True)
class Cylinder(_Shape):
    """A round link drawn from one named point to another.

    Attributes:
        between: the two end points' names; the length follows them every frame.
        radius: radius in metres (> 0).
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible.
    """

    kind: ClassVar[str] = "cylinder"
    between: tuple[str, str] = _field(_name_pair, point=True)
    radius: float = _field(_positive)
    color: Color = _field(_color, LINK_GREY)
    opacity: float = _field(_opacity, 1.0)


@dataclass(frozen=True)
class Box(_Shape):
    """A rectangular block, fixed in the world or carried by a named point.

    Attributes:
        center: a point name (the box follows it, keeping its rotation) or a
            fixed world position ``(x, y, z)`` in metres.
        size: edge lengths along the box's own x, y, z axes, metres (> 0).
        rotation: Euler angles in radians, applied as intrinsic rotations about
            x, then y, then z (``R = Rx @ Ry @ Rz``).
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible.
    """

    kind: ClassVar[str] = "box"
    center: tuple[float, float, float] | str = _field(_name_or_vec3, point=True)
    size: tuple[float, float, float] = _field(_size)
    rotation: tuple[float, float, float] = _field(_vec3, (0.0, 0.0, 0.0))
    color: Color = _field(_color, PALETTE[3])
    opacity: float = _field(_opacity, 1.0)


@dataclass(frozen=True)
class Ground(_Shape):
    """The walking surface: a plane through the origin, ``z = -x * tan(slope)``.

    Its length along the slope is chosen by :func:`amble.viz.scene.frames` to cover
    the motion with a margin; the viewer draws a grid on it so that motion is visible.

    Attributes:
        slope: downhill angle in radians, positive descends along +x;
            must lie in (-pi/2, pi/2).
        width: lateral (y) extent in metres, centred on y = 0.
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible (the grid stays visible).
        grid: spacing of the grid lines in metres, measured along the surface.
        height: the plane's height at x = 0, metres (``z = height - x tan(slope)``): a robot
            that is no walker stands on a floor at the lowest point it reaches.
    """

    kind: ClassVar[str] = "ground"
    slope: float = _field(_slope, 0.0)
    width: float = _field(_positive, 2.0)
    color: Color = _field(_color, GROUND_COLOR)
    opacity: float = _field(_opacity, 1.0)
    grid: float = _field(_positive, 0.1)
    height: float = _field(_finite, 0.0)

    def to_dict(self, extent: tuple[float, float] = (-5.0, 5.0)) -> dict[str, Any]:
        """Static properties in the scene format (``height`` only when not 0).

        Args:
            extent: range of the along-slope coordinate covered, metres.
        """
        out = {**super().to_dict(), "extent": [rounded(extent[0]), rounded(extent[1])]}
        if out.get("height") == 0:
            out.pop("height")
        return out


@dataclass(frozen=True)
class Mesh(_Shape):
    """Triangles carried by a named frame (a robot link), e.g. a URDF ``<visual>`` mesh.

    The triangles are stored once in the scene's ``meshes`` (see :func:`amble.viz.meshes.encode`)
    and the frame's pose per frame in its ``poses``; both are given to
    :func:`amble.viz.scene.frames`.

    Attributes:
        frame: name of the pose (link frame) the triangles are fixed to.
        mesh: key of the triangles in the scene's meshes, vertices in the frame's axes, metres.
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible.
    """

    kind: ClassVar[str] = "mesh"
    frame: str = _field(check_name)
    mesh: str = _field(check_name)
    color: Color = _field(_color, LINK_GREY)
    opacity: float = _field(_opacity, 1.0)


#: Anything :func:`amble.viz.scene.frames` can draw.
Shape = Sphere | Cylinder | Box | Ground | Mesh
