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
* The walking surface (:class:`Ground`) is a plane through ``(0, 0, height)``
  that descends along +x by the angle ``slope``: ``z = height - x * tan(slope)``.

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
                             "color": ..., "opacity": a, "height": z0},  # height: if not 0
        {"type": "mesh",     "frame": "thigh", "mesh": "thigh#0", "color": ..., "opacity": a}
      ],
      "poses":  {"thigh": [x0, y0, z0, qx0, qy0, qz0, qw0, x1, ...]},  # 7*F floats per frame
                                                # (metres; the rotation as a unit quaternion)
      "meshes": {"thigh#0": {"positions": b64, "indices": b64, "wide": false,
                             "lo": [x, y, z], "step": [dx, dy, dz], "triangles": n}},
      "follow": "hip" | null,                   # point the camera may track
      "labels": {"step": [0, 0, 1, ...]},        # F values per label (numbers or strings)
      "series": {"stance": [...], "energy": [...]},  # F numbers (or null) per time series
      "series_groups": [{"title": "angle", "unit": "rad", "series": ["stance", "swing"],
                         "units": ["rad", "rad"]}, ...],
                                                # the panels of the time-series plot, in order
      "time_unit": "s",                         # the unit of "times" on the plot's time axis
      "bounds": {"min": [x, y, z], "max": [x, y, z]}, # over all exported points and frames
      "size": d                                 # the robot's extent: largest bounding-box
                                                # diagonal of one frame, metres
    }

``poses`` and ``meshes`` are present when a shape is a mesh: a vertex is ``lo + k * step`` per
axis for the little-endian uint16 triples ``k`` of ``positions``, ``indices`` holds uint16 (uint32
when ``wide``) triangles, both base64 (see :mod:`amble.viz.meshes`); the bounds and ``size``
include the meshes' bounding boxes.

``series``, ``series_groups`` and ``time_unit`` are present when there is a time-series plot
(a scene without ``series_groups`` is shown with one panel per series).

Only points referenced by a shape (or by ``follow``) are exported. Numbers are
rounded to 1e-5, which is far below what a screen can show and keeps a 20 s,
60 fps walk to a few hundred kilobytes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from .errors import SceneError
from .frames import FORMAT, frames
from .shapes import PALETTE, Box, Color, Cylinder, Ground, Mesh, Shape, Sphere

__all__ = [
    "FORMAT",
    "Box",
    "Color",
    "Cylinder",
    "Ground",
    "Mesh",
    "Shape",
    "Sphere",
    "default_look",
    "frames",
]


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
        SceneError: a link or mass names a point that is not in ``point_names``,
            or a mass is negative or not finite.
    """
    names = list(point_names)
    known = set(names)
    for a, b in links:
        for n in (a, b):
            if n not in known:
                raise SceneError(f"default_look: link ({a!r}, {b!r}) names unknown point {n!r}")
    for n, m in masses.items():
        if n not in known:
            raise SceneError(f"default_look: mass given for unknown point {n!r}")
        if not (math.isfinite(float(m)) and float(m) >= 0.0):
            raise SceneError(f"default_look: mass of {n!r} must be >= 0, got {m!r}")

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
            color = PALETTE[i % len(PALETTE)]
        else:
            radius, color = r_min, (0.25, 0.27, 0.30)
        shapes.append(Sphere(at=name, radius=radius, color=color))
    return shapes
