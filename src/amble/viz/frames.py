"""Scene building: :func:`frames` combines shapes and per-frame point positions into the
JSON-serialisable ``amble.scene/1`` scene (described in :mod:`amble.viz.scene`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .errors import SceneError
from .shapes import DIGITS, Box, Ground, Mesh, Shape, check_name, rounded

__all__ = ["FORMAT", "frames"]

FORMAT = "amble.scene/1"


def frames(
    shapes: Sequence[Shape],
    points: Mapping[str, np.ndarray],
    times: np.ndarray,
    *,
    follow: str | None = None,
    labels: Mapping[str, Sequence[Any]] | None = None,
    series: Mapping[str, Sequence[float]] | None = None,
    series_groups: Sequence[Mapping[str, Any]] | None = None,
    time_unit: str = "s",
    poses: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    meshes: Mapping[str, dict[str, Any]] | None = None,
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
        series: time series drawn in the viewer's panel with a playhead, e.g.
            ``{"stance": values, "energy": values}``; each ``F`` numbers.
        series_groups: the panels of that plot, in order: ``{"title": str, "unit": str,
            "series": [names], "units": [str]}`` each (``units``, one per series, optional; default:
            one panel per series, titled by its name).
        time_unit: the unit of ``times`` shown on the plot's time axis.
        poses: frames that :class:`Mesh` shapes are fixed to, by name: positions ``(F, 3)`` in
            metres and rotations ``(F, 3, 3)`` (the frame's axes as columns, world coordinates).
        meshes: triangles of the :class:`Mesh` shapes by key, as :func:`amble.viz.meshes.encode`
            writes them.

    Returns:
        The scene dictionary described in :mod:`amble.viz.scene`.

    Raises:
        SceneError: a shape or ``follow`` names a point missing from ``points``,
            arrays have the wrong shape or length, values are not finite, or
            times decrease.
    """
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise SceneError(f"frames: times must be a non-empty 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise SceneError("frames: times must be finite")
    if np.any(np.diff(t) < 0):
        raise SceneError("frames: times must be non-decreasing")
    n = t.size

    grounds = [s for s in shapes if isinstance(s, Ground)]
    if len(grounds) > 1:
        raise SceneError(f"frames: at most one Ground, got {len(grounds)}")
    for s in shapes:
        if not isinstance(s, Shape):
            raise SceneError(f"frames: not a shape: {s!r}")

    needed: list[str] = []
    for s in shapes:
        needed.extend(s.points())
    if follow is not None:
        needed.append(check_name(follow, "follow", "frames"))
    needed = list(dict.fromkeys(needed))  # keep order, drop repeats
    missing = [p for p in needed if p not in points]
    if missing:
        raise SceneError(
            f"frames: unknown point name(s) {', '.join(map(repr, missing))}; "
            f"points given: {', '.join(map(repr, points)) or 'none'}"
        )

    arrays = {name: _as_xyz(name, points[name], n) for name in needed}
    pose_data, corners = _mesh_parts(shapes, poses or {}, meshes or {}, n)
    extent = [*arrays.values(), *corners]

    size = 0.0
    if extent:
        stacked = np.concatenate(extent, axis=0)
        lo, hi = stacked.min(axis=0), stacked.max(axis=0)
        # the robot's own size: the largest diagonal of its bounding box in any one frame (the
        # camera's distance; the bounds of the whole run are the walk's, not the robot's)
        per_frame = np.stack(extent, axis=0)  # (points, frames, 3)
        size = float(np.max(np.linalg.norm(per_frame.max(axis=0) - per_frame.min(axis=0), axis=1)))
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
        **({"series": _series(series, n), "series_groups": _groups(series, series_groups),
            "time_unit": str(time_unit)} if series else {}),
        **pose_data,
        "bounds": {"min": _flat(lo), "max": _flat(hi)},
        "size": rounded(size),
    }
    return scene


def _mesh_parts(shapes: Sequence[Shape], poses: Mapping[str, tuple[np.ndarray, np.ndarray]],
                meshes: Mapping[str, dict[str, Any]], n: int) -> tuple[dict[str, Any], list[np.ndarray]]:
    """The scene's ``poses`` (``[x, y, z, qx, qy, qz, qw]`` per frame, the rotation as a unit
    quaternion) and ``meshes`` used by :class:`Mesh` shapes, and the world positions ``(F, 3)`` of
    the corners of each mesh's bounding box (for the bounds and the robot's size)."""
    used = [s for s in shapes if isinstance(s, Mesh)]
    if not used:
        return {}, []
    from scipy.spatial.transform import Rotation  # here: importing it costs ~1 s, needed for meshes only

    out_poses: dict[str, list[float]] = {}
    corners: list[np.ndarray] = []
    for s in used:
        if s.frame not in poses:
            raise SceneError(f"frames: mesh on unknown frame {s.frame!r}; "
                             f"poses given: {', '.join(map(repr, poses)) or 'none'}")
        if s.mesh not in meshes:
            raise SceneError(f"frames: unknown mesh {s.mesh!r}")
        p, R = (np.asarray(a, dtype=float) for a in poses[s.frame])
        if p.shape != (n, 3) or R.shape != (n, 3, 3):
            raise SceneError(f"frames: pose {s.frame!r} must have shapes ({n}, 3) and ({n}, 3, 3), "
                             f"got {p.shape} and {R.shape}")
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(R))):
            raise SceneError(f"frames: pose {s.frame!r} has non-finite values")
        if s.frame not in out_poses:
            q = Rotation.from_matrix(R).as_quat()   # (x, y, z, w), as three.js stores it
            out_poses[s.frame] = _flat(np.column_stack([p, q]))
        m = meshes[s.mesh]
        lo = np.asarray(m["lo"], dtype=float)
        hi = lo + 65535 * np.asarray(m["step"], dtype=float)
        box = np.array([[(hi if (k >> a) & 1 else lo)[a] for a in range(3)] for k in range(8)])
        corners.extend(np.swapaxes(p[:, None, :] + box @ np.swapaxes(R, 1, 2), 0, 1))
    keys = dict.fromkeys(s.mesh for s in used)
    return {"poses": out_poses, "meshes": {k: dict(meshes[k]) for k in keys}}, corners


def _as_xyz(name: str, value: np.ndarray, n: int) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 2 and a.shape[1] == 2:
        # Planar models give (x, z); they live in the y = 0 plane.
        a = np.column_stack([a[:, 0], np.zeros(len(a)), a[:, 1]])
    if a.ndim != 2 or a.shape[1] != 3:
        raise SceneError(f"frames: point {name!r} must have shape (F, 3), got {a.shape}")
    if a.shape[0] != n:
        raise SceneError(f"frames: point {name!r} has {a.shape[0]} frames, times has {n}")
    if not np.all(np.isfinite(a)):
        raise SceneError(f"frames: point {name!r} has non-finite positions")
    return a


def _ground_extent(slope: float, x_min: float, x_max: float) -> tuple[float, float]:
    """Along-slope range that covers the motion, with room to spare on both ends."""
    span = float(x_max - x_min)
    margin = max(3.0, 0.5 * span)
    c = math.cos(slope)
    # The along-slope coordinate s of a point at x is x / cos(slope).
    return ((x_min - margin) / c, (x_max + margin) / c)


def _series(series: Mapping[str, Sequence[float]], n: int) -> dict[str, list[Any]]:
    """Time series for the viewer's panel: ``F`` numbers each (non-finite → null)."""
    out: dict[str, list[Any]] = {}
    for key, values in series.items():
        vals = np.asarray(values, dtype=float)
        if vals.shape != (n,):
            raise SceneError(f"frames: series {key!r} has shape {vals.shape}, times has {n}")
        out[str(key)] = [rounded(float(v)) if math.isfinite(v) else None for v in vals]
    return out


def _groups(series: Mapping[str, Sequence[float]], groups: Sequence[Mapping[str, Any]] | None
            ) -> list[dict[str, Any]]:
    """The panels of the time-series plot, each naming series that are given."""
    if groups is None:
        return [{"title": str(k), "unit": "", "series": [str(k)], "units": [""]} for k in series]
    out = []
    for g in groups:
        names = [str(k) for k in g.get("series", ())]
        missing = [k for k in names if k not in series]
        if missing or not names:
            raise SceneError(f"frames: series panel {g.get('title')!r} names "
                             + (f"unknown series {', '.join(map(repr, missing))}" if missing else "no series"))
        units = [str(u or "") for u in g.get("units") or [g.get("unit")] * len(names)]
        if len(units) != len(names):
            raise SceneError(f"frames: series panel {g.get('title')!r} has {len(units)} units for {len(names)} series")
        out.append({"title": str(g.get("title", names[0])), "unit": str(g.get("unit") or ""), "series": names,
                    "units": units})
    return out


def _labels(labels: Mapping[str, Sequence[Any]] | None, n: int) -> dict[str, list[Any]]:
    out: dict[str, list[Any]] = {}
    for key, values in (labels or {}).items():
        vals = list(values)
        if len(vals) != n:
            raise SceneError(f"frames: label {key!r} has {len(vals)} values, times has {n}")
        out[str(key)] = [_label_value(v) for v in vals]
    return out


def _label_value(v: Any) -> Any:
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return rounded(float(v)) if math.isfinite(v) else None
    return str(v)


def _flat(a: np.ndarray) -> list[float]:
    """Row-major flat list of rounded floats, integral values written as ints."""
    r = np.round(np.asarray(a, dtype=float).ravel(), DIGITS) + 0.0
    # JSON "0" is shorter than "0.0": planar models have a whole column of zeros.
    return [int(v) if v.is_integer() else v for v in r.tolist()]
