"""Visual geometry of a robot file, for the 3D viewer.

:func:`urdf_visuals` reads every ``<visual>`` of a URDF's links: a ``<mesh>`` (STL, OBJ, DAE, …,
loaded by `trimesh <https://trimesh.org>`_) with its ``scale``, or a ``<box>``, ``<cylinder>`` or
``<sphere>``, placed by the visual's ``<origin>`` — so each :class:`Visual` holds triangles in
its link's frame (metres). ``package://name/rest`` paths are looked up in the directories of
``ROS_PACKAGE_PATH``, in an ancestor directory of the URDF called ``name``, and then relative
to the URDF's directory and its ancestors (yourdfpy's ``filename_handler_magic``), which finds
the meshes of an installed ``example-robot-data``.

Published robots carry CAD meshes of hundreds of thousands of triangles; :func:`within_budget`
reduces them to a total budget by vertex clustering (the vertices in a cell of a uniform grid
merge into their mean, triangles that collapse are dropped), and :func:`encode` stores a mesh
as 16-bit integer positions over its bounding box (a step of extent / 65535: 8 µm for a
0.5 m link) and 16- or 32-bit indices, base64-encoded, so that a robot adds one or two
megabytes to the page.
"""

from __future__ import annotations

import base64
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SceneError
from .shapes import Color

__all__ = ["MAX_TRIANGLES", "Visual", "decimate", "encode", "mjcf_visuals", "resolve", "robot_visuals", "urdf_visuals",
           "within_budget"]

#: Triangles of all the meshes of one scene together (about 12 bytes each in the page).
MAX_TRIANGLES = 120_000
#: Colour of a visual whose file gives none (a light grey, like most CAD viewers).
DEFAULT_COLOR: Color = (0.72, 0.74, 0.78)


@dataclass(frozen=True)
class Visual:
    """The triangles of one ``<visual>`` of a link.

    Attributes:
        link: the link's name (its frame carries the triangles).
        vertices: ``(N, 3)`` positions in the link frame, metres (the visual's origin and scale
            applied).
        faces: ``(M, 3)`` vertex indices of the triangles.
        color: sRGB colour, floats in 0..1.
        opacity: 1 is opaque.
    """

    link: str
    vertices: np.ndarray
    faces: np.ndarray
    color: Color = DEFAULT_COLOR
    opacity: float = 1.0


def resolve(filename: str, urdf: str | Path) -> Path | None:
    """The file a URDF's mesh ``filename`` names (``package://``, ``file://`` or a path relative to
    the URDF), or ``None`` when it cannot be found."""
    urdf = Path(urdf).resolve()
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    candidates: list[Path] = []
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        for d in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
            if d:
                candidates += [Path(d) / package / rest, Path(d) / rest]
        candidates += [a / rest for a in urdf.parents if a.name == package]
    else:
        candidates.append(urdf.parent / filename)
    for c in candidates:
        if c.is_file():
            return c
    import yourdfpy

    found = Path(yourdfpy.filename_handler_magic(filename, dir=str(urdf.parent)))
    return found if found.is_file() else None


def _materials(robot: Any) -> dict[str, Color]:
    out = {}
    for m in robot.materials or ():
        if m.name and m.color is not None:
            out[m.name] = tuple(float(c) for c in m.color.rgba[:3])
    return out


def _color(visual: Any, named: dict[str, Color], mesh: Any) -> tuple[Color, float]:
    """The visual's colour and opacity: its ``<material>`` (inline or named at the robot's top),
    else the mesh file's own single colour, else :data:`DEFAULT_COLOR`."""
    mat = visual.material
    if mat is not None and mat.color is not None:
        rgba = np.clip(np.asarray(mat.color.rgba, dtype=float), 0.0, 1.0)
        return (float(rgba[0]), float(rgba[1]), float(rgba[2])), float(rgba[3])
    if mat is not None and mat.name in named:
        return named[mat.name], 1.0
    vis = getattr(mesh, "visual", None)
    if vis is not None and getattr(vis, "kind", None) in ("face", "vertex"):
        c = np.asarray(vis.main_color, dtype=float)[:3] / 255.0
        return (float(c[0]), float(c[1]), float(c[2])), 1.0
    return DEFAULT_COLOR, 1.0


def _geometry(geometry: Any, urdf: Path) -> Any:
    """The visual's shape as a ``trimesh.Trimesh`` in its own frame (scale applied), or ``None``
    for a mesh file that cannot be found or read (with a warning)."""
    import trimesh

    if geometry.box is not None:
        return trimesh.creation.box(extents=np.asarray(geometry.box.size, dtype=float))
    if geometry.cylinder is not None:   # URDF and trimesh: the axis is z, centred on the origin
        c = geometry.cylinder
        return trimesh.creation.cylinder(radius=float(c.radius), height=float(c.length), sections=24)
    if geometry.sphere is not None:
        return trimesh.creation.icosphere(subdivisions=2, radius=float(geometry.sphere.radius))
    if geometry.mesh is None:
        return None
    path = resolve(geometry.mesh.filename, urdf)
    if path is None:
        warnings.warn(f"URDF {urdf.name}: mesh {geometry.mesh.filename!r} not found; "
                      "its link is drawn without it", stacklevel=4)
        return None
    try:
        mesh = trimesh.load(str(path), force="mesh")
    except Exception as e:  # a file trimesh cannot read is drawn without it, not an error
        warnings.warn(f"URDF {urdf.name}: mesh {path.name} cannot be read ({e})", stacklevel=4)
        return None
    if geometry.mesh.scale is not None:
        mesh.apply_scale(np.broadcast_to(np.asarray(geometry.mesh.scale, dtype=float), 3))
    return mesh


def urdf_visuals(path: str | Path) -> list[Visual]:
    """Every ``<visual>`` of the URDF at ``path`` with triangles, in link order.

    A mesh file that cannot be found or read is left out with a warning (its link is drawn as a
    ball and stick).

    Raises:
        SceneError: the URDF cannot be parsed.
    """
    import yourdfpy

    path = Path(path)
    try:
        robot = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False,
                                   build_collision_scene_graph=False, load_collision_meshes=False).robot
    except Exception as e:
        raise SceneError(f"URDF {path.name}: cannot be read for drawing: {e}") from e
    named = _materials(robot)
    out = []
    for link in robot.links:
        for visual in link.visuals:
            mesh = _geometry(visual.geometry, path)
            if mesh is None or len(mesh.faces) == 0:
                continue
            T = np.eye(4) if visual.origin is None else np.asarray(visual.origin, dtype=float)
            v = np.asarray(mesh.vertices, dtype=float) @ T[:3, :3].T + T[:3, 3]
            color, opacity = _color(visual, named, mesh)
            out.append(Visual(link.name, v, np.asarray(mesh.faces, dtype=np.int64), color, opacity))
    return out


def _mjcf_shape(m: Any, g: int) -> Any:
    """Geom ``g`` of a compiled MuJoCo model as a ``trimesh.Trimesh`` in the geom's frame, or
    ``None`` (a plane, a height field)."""
    import mujoco
    import trimesh

    kind, size = int(m.geom_type[g]), np.asarray(m.geom_size[g], dtype=float)
    t = mujoco.mjtGeom
    if kind == t.mjGEOM_MESH:
        d = int(m.geom_dataid[g])
        v0, nv, f0, nf = m.mesh_vertadr[d], m.mesh_vertnum[d], m.mesh_faceadr[d], m.mesh_facenum[d]
        return trimesh.Trimesh(np.asarray(m.mesh_vert[v0:v0 + nv], dtype=float),
                               np.asarray(m.mesh_face[f0:f0 + nf], dtype=np.int64), process=False)
    if kind == t.mjGEOM_BOX:
        return trimesh.creation.box(extents=2 * size)
    if kind == t.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    if kind == t.mjGEOM_ELLIPSOID:
        ball = trimesh.creation.icosphere(subdivisions=2)
        ball.apply_scale(size)
        return ball
    if kind == t.mjGEOM_CYLINDER:        # MuJoCo's size: radius, half-length along z
        return trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=24)
    if kind == t.mjGEOM_CAPSULE:
        return trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=[24, 12])
    return None


def mjcf_visuals(path: str | Path) -> list[Visual]:
    """Every geom of the bodies (not the world's) of the MJCF at ``path`` that MuJoCo's viewer
    shows by default (groups 0 to 2, not transparent), placed in its body's frame (MuJoCo's
    ``geom_pos``, ``geom_quat``), coloured by ``geom_rgba`` or its material's ``mat_rgba``.

    Raises:
        SceneError: MuJoCo's compiler refuses the file.
    """
    import mujoco

    path = Path(path)
    try:
        m = mujoco.MjModel.from_xml_path(str(path))
    except Exception as e:
        raise SceneError(f"MJCF {path.name}: cannot be read for drawing: {e}") from e
    out = []
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        rgba = np.asarray(m.mat_rgba[m.geom_matid[g]] if m.geom_matid[g] >= 0 else m.geom_rgba[g], dtype=float)
        if b == 0 or m.geom_group[g] > 2 or rgba[3] == 0:
            continue
        mesh = _mjcf_shape(m, g)
        if mesh is None or len(mesh.faces) == 0:
            continue
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, np.asarray(m.geom_quat[g], dtype=float))
        v = np.asarray(mesh.vertices, dtype=float) @ R.reshape(3, 3).T + m.geom_pos[g]
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
        rgb = np.clip(rgba[:3], 0.0, 1.0)
        out.append(Visual(name, v, np.asarray(mesh.faces, dtype=np.int64),
                          (float(rgb[0]), float(rgb[1]), float(rgb[2])), float(np.clip(rgba[3], 0, 1))))
    return out


def robot_visuals(path: str | Path) -> list[Visual]:
    """The visuals of a robot file: :func:`mjcf_visuals` for ``.xml`` / ``.mjcf``, else
    :func:`urdf_visuals`."""
    if Path(path).suffix.lower() in (".xml", ".mjcf"):
        return mjcf_visuals(path)
    return urdf_visuals(path)


def _cluster(v: np.ndarray, f: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertex clustering on a grid of ``cell`` metres: one vertex (the mean) per occupied cell,
    collapsed and repeated triangles dropped (orientation kept)."""
    cells = np.floor((v - v.min(axis=0)) / cell).astype(np.int64)
    size = cells.max(axis=0) + 1   # one integer per cell: a 1-D unique is much faster
    keys = (cells[:, 0] * size[1] + cells[:, 1]) * size[2] + cells[:, 2]
    _, inverse = np.unique(keys, return_inverse=True)
    inverse = inverse.ravel()
    n = int(inverse.max()) + 1
    counts = np.bincount(inverse, minlength=n).astype(float)
    merged = np.column_stack([np.bincount(inverse, weights=v[:, k], minlength=n) for k in range(3)])
    merged /= counts[:, None]
    g = inverse[f]
    keep = (g[:, 0] != g[:, 1]) & (g[:, 1] != g[:, 2]) & (g[:, 0] != g[:, 2])
    g = g[keep]
    s = np.sort(g, axis=1)
    _, first = np.unique((s[:, 0] * n + s[:, 1]) * n + s[:, 2], return_index=True)
    g = g[np.sort(first)]
    used, g = np.unique(g, return_inverse=True)
    return merged[used], g.reshape(-1, 3)


def decimate(vertices: np.ndarray, faces: np.ndarray, max_faces: int) -> tuple[np.ndarray, np.ndarray]:
    """At most ``max_faces`` triangles of the mesh, by vertex clustering on the finest grid that
    keeps within the count (bisection on the cell size); a mesh within the count is returned as
    it is."""
    v, f = np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)
    if len(f) <= max_faces:
        return v, f
    extent = float(np.max(v.max(axis=0) - v.min(axis=0)))
    if extent == 0.0:
        return v[:0], f[:0]
    lo, hi = extent * 1e-4, extent   # a cell the mesh's size leaves no triangle
    best = _cluster(v, f, hi)
    for _ in range(10):
        mid = np.sqrt(lo * hi)
        cand = _cluster(v, f, mid)
        if len(cand[1]) <= max_faces:
            best, hi = cand, mid
        else:
            lo = mid
    return best


def within_budget(visuals: Sequence[Visual], max_triangles: int = MAX_TRIANGLES) -> list[Visual]:
    """The visuals with at most ``max_triangles`` triangles together: each mesh keeps a share
    proportional to its own count (at least 48), those already small stay as they are."""
    total = sum(len(vis.faces) for vis in visuals)
    if total <= max_triangles:
        return list(visuals)
    out = []
    for vis in visuals:
        share = max(48, int(max_triangles * len(vis.faces) / total))
        v, f = decimate(vis.vertices, vis.faces, share)
        if len(f):
            out.append(Visual(vis.link, v, f, vis.color, vis.opacity))
    return out


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a).astype(a.dtype.newbyteorder("<")).tobytes()).decode("ascii")


def encode(vertices: np.ndarray, faces: np.ndarray) -> dict[str, Any]:
    """A mesh in the scene format: ``positions`` (base64 of little-endian uint16 triples, the
    position is ``lo + k * step`` per axis, metres), ``indices`` (base64 of little-endian uint16,
    or uint32 when ``wide``), ``lo``, ``step`` and the ``triangles`` count."""
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces, dtype=np.int64)
    lo, hi = v.min(axis=0), v.max(axis=0)
    step = (hi - lo) / 65535.0   # 0 along a flat axis: every vertex at lo
    k = np.clip(np.rint((v - lo) / np.where(step > 0, step, 1.0)), 0, 65535).astype(np.uint16)
    wide = len(v) > 65535
    return {
        "positions": _b64(k),
        "indices": _b64(f.astype(np.uint32 if wide else np.uint16)),
        "wide": wide,
        "lo": [float(x) for x in lo],
        "step": [float(x) for x in step],
        "triangles": int(len(f)),
    }


def decode(mesh: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The vertices ``(N, 3)`` and faces ``(M, 3)`` of a mesh written by :func:`encode`."""
    k = np.frombuffer(base64.b64decode(mesh["positions"]), dtype="<u2").reshape(-1, 3)
    f = np.frombuffer(base64.b64decode(mesh["indices"]), dtype="<u4" if mesh["wide"] else "<u2")
    return np.asarray(mesh["lo"]) + k * np.asarray(mesh["step"]), f.reshape(-1, 3).astype(np.int64)
