"""Scene description for the 3D viewer.

A model declares its *look* as a list of shapes bound to named points. The
simulator computes the world position of every point at every output time;
:func:`frames` combines both into a compact, JSON-serialisable scene that
:func:`amble.viz.html.write_html` turns into an offline animation.

Conventions
-----------
* Units: metres, radians, seconds. Colours are sRGB triples of floats in 0..1.
* World frame: x forward (the downhill walking direction), y lateral (left),
  z up. Planar (2D) models live in the x-z plane, y = 0.
* The walking surface (:class:`Ground`) is a plane through the world origin
  that descends along +x by the angle ``slope``: ``z = -x * tan(slope)``.

Scene format (``"format": "amble.scene/1"``)
--------------------------------------------
::

    {
      "format": "amble.scene/1",
      "times":  [t0, t1, ...],                  # F floats, seconds, non-decreasing
      "points": {"hip": [x0, y0, z0, x1, ...]}, # 3*F floats per point, metres
      "shapes": [                               # drawn in this order
        {"type": "sphere",   "at": "hip", "radius": r, "color": [r, g, b], "opacity": a},
        {"type": "cylinder", "between": ["hip", "foot"], "radius": r, "color": ..., "opacity": a},
        {"type": "box",      "center": "hip" | [x, y, z], "size": [sx, sy, sz],
                             "rotation": [rx, ry, rz], "color": ..., "opacity": a},
        {"type": "ground",   "slope": s, "width": w, "grid": g, "extent": [s0, s1],
                             "color": ..., "opacity": a}
      ],
      "follow": "hip" | null,                   # point the camera may track
      "labels": {"step": [0, 0, 1, ...]},        # F values per label (numbers or strings)
      "bounds": {"min": [x, y, z], "max": [x, y, z]}  # over all exported points and frames
    }

Only points referenced by a shape (or by ``follow``) are exported. Numbers are
rounded to 1e-5, which is far below what a screen can show and keeps a 20 s,
60 fps walk to a few hundred kilobytes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "Box",
    "Color",
    "Cylinder",
    "Ground",
    "Shape",
    "Sphere",
    "default_look",
    "frames",
]

#: An sRGB colour, three floats in 0..1.
Color = tuple[float, float, float]

FORMAT = "amble.scene/1"

#: Decimal places kept in the scene: 1e-5 m / 1e-5 s.
_DIGITS = 5

_LINK_GREY: Color = (0.62, 0.64, 0.68)
_GROUND_COLOR: Color = (0.86, 0.88, 0.91)
# Softened categorical palette, so neighbouring points are told apart at a glance.
_PALETTE: tuple[Color, ...] = (
    (0.90, 0.30, 0.24),
    (0.20, 0.47, 0.80),
    (0.30, 0.69, 0.40),
    (0.95, 0.61, 0.13),
    (0.58, 0.40, 0.74),
    (0.10, 0.70, 0.75),
    (0.85, 0.40, 0.65),
    (0.55, 0.45, 0.35),
)


def _check_color(color: Sequence[float], owner: str) -> Color:
    try:
        c = tuple(float(v) for v in color)
    except TypeError as exc:
        raise ValueError(f"{owner}: color must be three floats in 0..1, got {color!r}") from exc
    if len(c) != 3 or not all(0.0 <= v <= 1.0 for v in c):
        raise ValueError(f"{owner}: color must be three floats in 0..1, got {color!r}")
    return c  # type: ignore[return-value]


def _check_opacity(opacity: float, owner: str) -> float:
    a = float(opacity)
    if not 0.0 <= a <= 1.0:
        raise ValueError(f"{owner}: opacity must be in 0..1, got {opacity!r}")
    return a


def _check_positive(value: float, what: str, owner: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{owner}: {what} must be a positive finite number, got {value!r}")
    return v


def _check_vec3(value: Sequence[float], what: str, owner: str) -> tuple[float, float, float]:
    try:
        v = tuple(float(x) for x in value)
    except TypeError as exc:
        raise ValueError(f"{owner}: {what} must be three floats, got {value!r}") from exc
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise ValueError(f"{owner}: {what} must be three finite floats, got {value!r}")
    return v  # type: ignore[return-value]


def _check_name(name: object, what: str, owner: str) -> str:
    if not isinstance(name, str) or not name:
        raise ValueError(f"{owner}: {what} must be a non-empty point name, got {name!r}")
    return name


@dataclass(frozen=True)
class Sphere:
    """A ball centred on a named point.

    Attributes:
        at: name of the point the sphere follows.
        radius: radius in metres (> 0).
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible.
    """

    at: str
    radius: float
    color: Color = _PALETTE[1]
    opacity: float = 1.0

    def __post_init__(self) -> None:
        _check_name(self.at, "at", "Sphere")
        object.__setattr__(self, "radius", _check_positive(self.radius, "radius", "Sphere"))
        object.__setattr__(self, "color", _check_color(self.color, "Sphere"))
        object.__setattr__(self, "opacity", _check_opacity(self.opacity, "Sphere"))

    def points(self) -> tuple[str, ...]:
        """Names of the points this shape needs."""
        return (self.at,)

    def to_dict(self) -> dict[str, Any]:
        """Static properties in the scene format."""
        return {
            "type": "sphere",
            "at": self.at,
            "radius": _r(self.radius),
            "color": [_r(c) for c in self.color],
            "opacity": _r(self.opacity),
        }


@dataclass(frozen=True)
class Cylinder:
    """A round link drawn from one named point to another.

    Attributes:
        between: the two end points' names; the length follows them every frame.
        radius: radius in metres (> 0).
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible.
    """

    between: tuple[str, str]
    radius: float
    color: Color = _LINK_GREY
    opacity: float = 1.0

    def __post_init__(self) -> None:
        ends = tuple(self.between)
        if len(ends) != 2:
            raise ValueError(f"Cylinder: between must be two point names, got {self.between!r}")
        for name in ends:
            _check_name(name, "between", "Cylinder")
        object.__setattr__(self, "between", ends)
        object.__setattr__(self, "radius", _check_positive(self.radius, "radius", "Cylinder"))
        object.__setattr__(self, "color", _check_color(self.color, "Cylinder"))
        object.__setattr__(self, "opacity", _check_opacity(self.opacity, "Cylinder"))

    def points(self) -> tuple[str, ...]:
        """Names of the points this shape needs."""
        return tuple(self.between)

    def to_dict(self) -> dict[str, Any]:
        """Static properties in the scene format."""
        return {
            "type": "cylinder",
            "between": list(self.between),
            "radius": _r(self.radius),
            "color": [_r(c) for c in self.color],
            "opacity": _r(self.opacity),
        }


@dataclass(frozen=True)
class Box:
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

    center: tuple[float, float, float] | str
    size: tuple[float, float, float]
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    color: Color = _PALETTE[3]
    opacity: float = 1.0

    def __post_init__(self) -> None:
        if isinstance(self.center, str):
            _check_name(self.center, "center", "Box")
        else:
            object.__setattr__(self, "center", _check_vec3(self.center, "center", "Box"))
        size = _check_vec3(self.size, "size", "Box")
        for s in size:
            _check_positive(s, "size", "Box")
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "rotation", _check_vec3(self.rotation, "rotation", "Box"))
        object.__setattr__(self, "color", _check_color(self.color, "Box"))
        object.__setattr__(self, "opacity", _check_opacity(self.opacity, "Box"))

    def points(self) -> tuple[str, ...]:
        """Names of the points this shape needs."""
        return (self.center,) if isinstance(self.center, str) else ()

    def to_dict(self) -> dict[str, Any]:
        """Static properties in the scene format."""
        center = self.center if isinstance(self.center, str) else [_r(c) for c in self.center]
        return {
            "type": "box",
            "center": center,
            "size": [_r(s) for s in self.size],
            "rotation": [_r(a) for a in self.rotation],
            "color": [_r(c) for c in self.color],
            "opacity": _r(self.opacity),
        }


@dataclass(frozen=True)
class Ground:
    """The walking surface: a plane through the origin, ``z = -x * tan(slope)``.

    Its length along the slope is chosen by :func:`frames` to cover the motion
    with a margin; the viewer draws a grid on it so that motion is visible.

    Attributes:
        slope: downhill angle in radians, positive descends along +x;
            must lie in (-pi/2, pi/2).
        width: lateral (y) extent in metres, centred on y = 0.
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque, 0 is invisible (the grid stays visible).
        grid: spacing of the grid lines in metres, measured along the surface.
    """

    slope: float = 0.0
    width: float = 2.0
    color: Color = _GROUND_COLOR
    opacity: float = 1.0
    grid: float = 0.1

    def __post_init__(self) -> None:
        slope = float(self.slope)
        if not (math.isfinite(slope) and abs(slope) < math.pi / 2):
            raise ValueError(f"Ground: slope must be in (-pi/2, pi/2) radians, got {self.slope!r}")
        object.__setattr__(self, "slope", slope)
        object.__setattr__(self, "width", _check_positive(self.width, "width", "Ground"))
        object.__setattr__(self, "color", _check_color(self.color, "Ground"))
        object.__setattr__(self, "opacity", _check_opacity(self.opacity, "Ground"))
        object.__setattr__(self, "grid", _check_positive(self.grid, "grid", "Ground"))

    def points(self) -> tuple[str, ...]:
        """Names of the points this shape needs (none)."""
        return ()

    def to_dict(self, extent: tuple[float, float] = (-5.0, 5.0)) -> dict[str, Any]:
        """Static properties in the scene format.

        Args:
            extent: range of the along-slope coordinate covered, metres.
        """
        return {
            "type": "ground",
            "slope": _r(self.slope),
            "width": _r(self.width),
            "grid": _r(self.grid),
            "extent": [_r(extent[0]), _r(extent[1])],
            "color": [_r(c) for c in self.color],
            "opacity": _r(self.opacity),
        }


#: Anything :func:`frames` can draw.
Shape = Sphere | Cylinder | Box | Ground


def default_look(
    point_names: Sequence[str],
    links: Sequence[tuple[str, str]],
    masses: Mapping[str, float],
    *,
    slope: float | None = 0.0,
) -> list[Shape]:
    """A plain look for a model that declares none.

    Every named point gets a sphere whose volume is proportional to its mass
    (radius ~ cube root of mass, 8 cm for the heaviest point); massless points
    get a small 2 cm marker. Every link becomes a grey cylinder.

    Args:
        point_names: names of the model's points, in drawing order.
        links: pairs of point names joined by a rigid link.
        masses: mass in kg per point name; missing names count as massless.
        slope: downhill angle of the ground in radians, or ``None`` for no ground.

    Returns:
        Shapes for :func:`frames`: ground first, then links, then spheres (so
        joints are drawn over the ends of links).

    Raises:
        ValueError: a link or mass names a point that is not in ``point_names``,
            or a mass is negative or not finite.
    """
    names = list(point_names)
    known = set(names)
    for a, b in links:
        for n in (a, b):
            if n not in known:
                raise ValueError(f"default_look: link ({a!r}, {b!r}) names unknown point {n!r}")
    for n, m in masses.items():
        if n not in known:
            raise ValueError(f"default_look: mass given for unknown point {n!r}")
        if not (math.isfinite(float(m)) and float(m) >= 0.0):
            raise ValueError(f"default_look: mass of {n!r} must be >= 0, got {m!r}")

    m_max = max((float(m) for m in masses.values()), default=0.0)
    r_max, r_min, r_link = 0.08, 0.02, 0.015

    shapes: list[Shape] = []
    if slope is not None:
        shapes.append(Ground(slope=slope))
    shapes.extend(Cylinder(between=(a, b), radius=r_link) for a, b in links)
    for i, name in enumerate(names):
        m = float(masses.get(name, 0.0))
        if m > 0.0 and m_max > 0.0:
            # Scale-free in mass units: a normalised model looks like a dimensional one.
            radius = max(r_min, r_max * (m / m_max) ** (1.0 / 3.0))
            color = _PALETTE[i % len(_PALETTE)]
        else:
            radius, color = r_min, (0.25, 0.27, 0.30)
        shapes.append(Sphere(at=name, radius=radius, color=color))
    return shapes


def frames(
    shapes: Sequence[Shape],
    points: Mapping[str, np.ndarray],
    times: np.ndarray,
    *,
    follow: str | None = None,
    labels: Mapping[str, Sequence[Any]] | None = None,
) -> dict[str, Any]:
    """Build the JSON-serialisable scene the viewer animates.

    Args:
        shapes: the look: :class:`Sphere`, :class:`Cylinder`, :class:`Box` and at
            most one :class:`Ground`.
        points: world positions per point name, arrays of shape ``(F, 3)`` in
            metres (``(F, 2)`` is read as ``(x, z)`` of a planar model, y = 0).
        times: the ``F`` frame times in seconds, non-decreasing (equal
            neighbours are allowed, e.g. just before and after an impact).
        follow: a point name the camera can track, typically the hip.
        labels: extra per-frame values shown next to the clock, e.g.
            ``{"step": step_index}``; each a sequence of ``F`` numbers or strings.

    Returns:
        The scene dictionary described in this module's docstring.

    Raises:
        ValueError: a shape or ``follow`` names a point missing from ``points``,
            arrays have the wrong shape or length, values are not finite, or
            times decrease.
    """
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError(f"frames: times must be a non-empty 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("frames: times must be finite")
    if np.any(np.diff(t) < 0):
        raise ValueError("frames: times must be non-decreasing")
    n = t.size

    grounds = [s for s in shapes if isinstance(s, Ground)]
    if len(grounds) > 1:
        raise ValueError(f"frames: at most one Ground, got {len(grounds)}")
    for s in shapes:
        if not isinstance(s, (Sphere, Cylinder, Box, Ground)):
            raise ValueError(f"frames: not a shape: {s!r}")

    needed: list[str] = []
    for s in shapes:
        needed.extend(s.points())
    if follow is not None:
        needed.append(_check_name(follow, "follow", "frames"))
    needed = list(dict.fromkeys(needed))  # keep order, drop repeats
    missing = [p for p in needed if p not in points]
    if missing:
        raise ValueError(
            f"frames: unknown point name(s) {', '.join(map(repr, missing))}; "
            f"points given: {', '.join(map(repr, points)) or 'none'}"
        )

    arrays = {name: _as_xyz(name, points[name], n) for name in needed}

    if arrays:
        stacked = np.concatenate(list(arrays.values()), axis=0)
        lo, hi = stacked.min(axis=0), stacked.max(axis=0)
    else:
        static = [s.center for s in shapes if isinstance(s, Box)]
        lo = np.min(static, axis=0) if static else np.zeros(3)
        hi = np.max(static, axis=0) if static else np.zeros(3)

    shape_dicts: list[dict[str, Any]] = []
    for s in shapes:
        if isinstance(s, Ground):
            shape_dicts.append(s.to_dict(_ground_extent(s.slope, lo[0], hi[0])))
        else:
            shape_dicts.append(s.to_dict())

    scene: dict[str, Any] = {
        "format": FORMAT,
        "times": _flat(t),
        "points": {name: _flat(a) for name, a in arrays.items()},
        "shapes": shape_dicts,
        "follow": follow,
        "labels": _labels(labels, n),
        "bounds": {"min": _flat(lo), "max": _flat(hi)},
    }
    return scene


def _as_xyz(name: str, value: np.ndarray, n: int) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 2 and a.shape[1] == 2:
        # Planar models give (x, z); they live in the y = 0 plane.
        a = np.column_stack([a[:, 0], np.zeros(len(a)), a[:, 1]])
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"frames: point {name!r} must have shape (F, 3), got {a.shape}")
    if a.shape[0] != n:
        raise ValueError(f"frames: point {name!r} has {a.shape[0]} frames, times has {n}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"frames: point {name!r} has non-finite positions")
    return a


def _ground_extent(slope: float, x_min: float, x_max: float) -> tuple[float, float]:
    """Along-slope range that covers the motion, with room to spare on both ends."""
    span = float(x_max - x_min)
    margin = max(3.0, 0.5 * span)
    c = math.cos(slope)
    # The along-slope coordinate s of a point at x is x / cos(slope).
    return ((x_min - margin) / c, (x_max + margin) / c)


def _labels(labels: Mapping[str, Sequence[Any]] | None, n: int) -> dict[str, list[Any]]:
    out: dict[str, list[Any]] = {}
    for key, values in (labels or {}).items():
        vals = list(values)
        if len(vals) != n:
            raise ValueError(f"frames: label {key!r} has {len(vals)} values, times has {n}")
        out[str(key)] = [_label_value(v) for v in vals]
    return out


def _label_value(v: Any) -> Any:
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return _r(float(v)) if math.isfinite(v) else None
    return str(v)


def _r(x: float) -> float:
    """Round to the scene precision; ``+ 0.0`` turns -0.0 into 0.0."""
    return round(float(x), _DIGITS) + 0.0


def _flat(a: np.ndarray) -> list[float]:
    """Row-major flat list of rounded floats, integral values written as ints."""
    r = np.round(np.asarray(a, dtype=float).ravel(), _DIGITS) + 0.0
    # JSON "0" is shorter than "0.0": planar models have a whole column of zeros.
    return [int(v) if v.is_integer() else v for v in r.tolist()]
