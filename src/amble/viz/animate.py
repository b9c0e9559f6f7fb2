"""Animations of a trajectory: a self-contained 3D HTML viewer, or GIF/MP4 through matplotlib."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import AmbleError
from ..modelling.hybrid import HybridSystem
from ..modelling.walker import Walker
from ..simulation.trajectory import Trajectory
from .errors import SceneError, VizError
from .scene import Cylinder, Ground, Mesh, Shape, Sphere, default_look, frames


def look_of(system: HybridSystem, params: dict[str, float], look: Sequence[Any] | None = None) -> list[Any]:
    """The shapes that draw a system: ``look`` if given (with a walker's ground added), else a
    default from its masses and links (and a walker's slope). Only a :class:`Walker` has a ground."""
    slope = _slope(system, params) if isinstance(system, Walker) else None
    if look:
        shapes = list(look)
        for s in shapes:
            if not isinstance(s, Shape):
                raise SceneError(f"look: not a shape (Sphere, Cylinder, Box or Ground): {s!r}")
        if slope is not None and not any(isinstance(s, Ground) for s in shapes):
            shapes.insert(0, Ground(slope=slope))
        return shapes
    masses: dict[str, float] = {}
    links: list[tuple[str, str]] = []
    for m in system.modes.values():
        subs = {s: params.get(str(s), v) for s, v in m.params.items()}
        for name, mass in m.masses.items():
            masses[name] = max(masses.get(name, 0.0), float(mass.subs(subs)))
        links += [lk for lk in m.links if lk not in links]
    shapes = default_look(system.point_names, links, masses, slope=slope)
    # Legs swap names at every footfall; colouring spheres by mass keeps a leg's colour fixed.
    colours: dict[float, Any] = {}
    out = []
    for s in shapes:
        if isinstance(s, Sphere) and masses.get(s.at, 0.0) > 0:
            s = replace(s, color=colours.setdefault(round(masses[s.at], 9), s.color))
        out.append(s)
    return out


def floor_under(shapes: Sequence[Any], points: dict[str, np.ndarray], extra: Sequence[np.ndarray] = ()) -> Ground:
    """A level floor for a robot that declares no ground (a fixed-base arm, a falling robot): at
    the lowest point the drawing reaches over the run — the lowest point less the radius of its
    sphere, if it has one, or the lowest of the ``extra`` positions ``(F, 3)`` (the corners of
    its meshes) — and wide enough for the robot's lateral reach (m)."""
    radius = {s.at: s.radius for s in shapes if isinstance(s, Sphere)}
    low = min([float(np.min(v[:, 2])) - radius.get(n, 0.0) for n, v in points.items()]
              + [float(np.min(v[..., 2])) for v in extra])
    reach = max([float(np.max(np.abs(v[:, 1]))) + radius.get(n, 0.0) for n, v in points.items()]
                + [float(np.max(np.abs(v[..., 1]))) for v in extra])
    return Ground(slope=0.0, height=low, width=max(2.0, 2.0 * reach + 1.0))


def with_meshes(traj: Trajectory, times: np.ndarray, shapes: list[Any], max_triangles: int
                ) -> tuple[list[Any], dict, dict, list[np.ndarray]]:
    """The default look of a robot read from a URDF (or MJCF) with its visual meshes fixed to its
    links (at most ``max_triangles`` triangles together): the balls and sticks of the links that
    have a mesh, and of the massless link frames, are left out. Returns the shapes, the poses and
    meshes for :func:`frames`, and the world corners ``(F, 8, 3)`` of each mesh's bounding box;
    unchanged (no meshes) for a model built in code."""
    from .links import link_poses, robot_file
    from .meshes import encode, robot_visuals, within_budget

    path = robot_file(traj.system)
    if path is None:
        return shapes, {}, {}, []
    visuals = within_budget(robot_visuals(path), max_triangles)
    poses = link_poses(traj, times, {v.link for v in visuals})
    if any(np.any(np.linalg.det(np.nan_to_num(R)) < 0) for _, R in poses.values()):
        return shapes, {}, {}, []   # a walker whose frame change mirrors it: a mesh cannot be turned so
    poses = {k: (np.nan_to_num(p), np.nan_to_num(R)) for k, (p, R) in poses.items()}
    meshes, drawn, corners = {}, [], []
    for k, v in enumerate(visuals):
        if v.link not in poses:
            continue
        key = f"{v.link}#{k}"
        meshes[key] = encode(v.vertices, v.faces)
        drawn.append(Mesh(frame=v.link, mesh=key, color=v.color, opacity=v.opacity))
        lo, hi = v.vertices.min(axis=0), v.vertices.max(axis=0)
        box = np.array([[(hi if (i >> a) & 1 else lo)[a] for a in range(3)] for i in range(8)])
        p, R = poses[v.link]
        corners.append(p[:, None, :] + box @ np.swapaxes(R, 1, 2))
    if not drawn:
        return shapes, {}, {}, []
    tree = next(iter(traj.system.modes.values())).tree
    covered = {m.frame for m in drawn} | set(tree.link_frames)
    kept = [s for s in shapes
            if not (isinstance(s, Sphere) and s.at in covered)
            and not (isinstance(s, Cylinder) and set(s.between) & covered)]
    return [*kept, *drawn], poses, meshes, corners


def _slope(system: HybridSystem, params: dict[str, float]) -> float:
    return system.slope_value(params) if isinstance(system, Walker) else 0.0


#: A panel title for the quantity a unit measures (the unit itself if not listed).
QUANTITIES = {"rad": "angle", "deg": "angle", "rad/s": "angular velocity", "m": "position",
              "m/s": "velocity", "J": "energy", "N·m": "torque", "N*m": "torque", "N": "force",
              "W": "power", "s": "time"}

#: The ``series`` argument: names (grouped by unit), or panel title → names, or ``None``.
SeriesSpec = Sequence[str] | Mapping[str, Sequence[str]] | None


def _series_unit(traj: Trajectory, name: str) -> str:
    """The unit of a series (``""`` if undeclared or unknown: :func:`series_of` rejects the latter)."""
    try:
        return traj.unit("kinetic_energy" if name == "energy" else name)
    except AmbleError:
        return ""


def series_groups(traj: Trajectory, series: SeriesSpec) -> list[dict[str, Any]]:
    """The panels of the viewer's time-series plot: ``[{"title", "unit", "series": [names],
    "units": [each series' unit]}]``.

    ``series`` is a mapping of panel title → names (one panel each, in order, e.g.
    ``{"left leg": ["q1", "q2"], "right leg": ["q3", "q4"]}``), or a list of names, which share a
    panel when they share a unit (``"rad"``: titled ``"angle"``, ``"J"``: ``"energy"``, …; a name
    without a unit gets a panel of its own), or ``None``: the coordinates of the first mode and
    ``"energy"``. A panel's ``unit`` is its series' common unit (``""`` if they differ)."""
    if series is None:
        series = [*(str(q) for q in traj.system.modes[traj.mode_names[0]].q), "energy"]
    if isinstance(series, str):
        series = [series]
    if isinstance(series, Mapping):
        groups = []
        for title, names in series.items():
            names = [names] if isinstance(names, str) else [str(n) for n in names]
            if not names:
                raise SceneError(f"series: panel {title!r} names no series")
            units = {_series_unit(traj, n) for n in names}
            groups.append({"title": str(title), "unit": units.pop() if len(units) == 1 else "",
                           "series": names, "units": [_series_unit(traj, n) for n in names]})
        return groups
    by_unit: dict[str, dict[str, Any]] = {}
    out: list[dict[str, Any]] = []
    for name in (str(n) for n in series):
        unit = _series_unit(traj, name)
        if unit and unit in by_unit:
            by_unit[unit]["series"].append(name)
            by_unit[unit]["units"].append(unit)
            continue
        group = {"title": QUANTITIES.get(unit, unit) if unit else name, "unit": unit, "series": [name],
                 "units": [unit]}
        out.append(group)
        if unit:
            by_unit[unit] = group
    return out


def series_of(traj: Trajectory, times: np.ndarray, names: SeriesSpec) -> dict[str, np.ndarray]:
    """Values at ``times`` of state variables by name and ``"energy"`` (total), for the viewer's
    panel; default: the coordinates of the first mode and the energy. ``names`` may also be a
    mapping of panel title → names (see :func:`series_groups`)."""
    if names is None:
        names = [*(str(q) for q in traj.system.modes[traj.mode_names[0]].q), "energy"]
    if isinstance(names, str):
        names = [names]
    if isinstance(names, Mapping):
        names = [n for group in series_groups(traj, names) for n in group["series"]]
    table = traj.table()
    out = {}
    for name in names:
        if name == "energy":
            col = table["kinetic_energy"] + table["potential_energy"]
        elif name in table and name not in ("t", "mode"):
            col = np.asarray(table[name], float)
        else:
            raise SceneError(f"series: unknown column {name!r}; known: {', '.join(list(table)[2:])}, energy")
        idx = np.clip(np.searchsorted(traj.t, times, side="right") - 1, 0, len(traj.t) - 1)
        out[name] = col[idx]  # the last sample at or before each frame
    return out


def scene_of(traj: Trajectory, fps: float = 60.0, look: Sequence[Any] | None = None,
             series: SeriesSpec = None, max_triangles: int | None = None) -> dict:
    """Scene JSON (see :func:`amble.viz.scene.frames`) of a trajectory in world coordinates, with
    a time-series panel of ``series`` in panels (see :func:`series_groups`; ``[]`` for none). Without a
    ``look``, a robot read from a URDF is drawn with its visual meshes, at most ``max_triangles``
    triangles (default :data:`amble.viz.meshes.MAX_TRIANGLES`; 0 draws balls and sticks)."""
    from .meshes import MAX_TRIANGLES

    system = traj.system
    times, pts = traj.resample(fps)
    shapes = look_of(system, traj.parameters, look)
    poses: dict = {}
    meshes: dict = {}
    corners: list[np.ndarray] = []
    budget = MAX_TRIANGLES if max_triangles is None else int(max_triangles)
    if not look and budget > 0:
        shapes, poses, meshes, corners = with_meshes(traj, times, shapes, budget)
    walker = isinstance(system, Walker)
    hip = system.hip if walker else None
    follow = hip if hip in pts else None
    used = {n for s in shapes for n in s.points()}
    pts = {n: np.nan_to_num(v) for n, v in pts.items() if n in used or n == follow}
    if not any(isinstance(s, Ground) for s in shapes) and (pts or corners):
        shapes = [floor_under(shapes, pts, corners), *shapes]
    labels = {}
    if walker:  # a step count means something for a walker only
        labels["step"] = np.searchsorted([e.t for e in traj.step_events], times, side="right").tolist()
    values = series_of(traj, times, series)
    groups = series_groups(traj, series) if values else None
    return frames(shapes, pts, times, follow=follow, labels=labels, series=values, series_groups=groups,
                  time_unit=system.time_unit, poses=poses, meshes=meshes)


def movie_look(traj: Trajectory, path: str | Path, fps: float, look: Sequence[Any] | None = None,
               max_triangles: int | None = None) -> tuple[list[Any], Any]:
    """The shapes of a movie of ``traj`` and, for a robot read from a URDF or MJCF file (without
    a ``look``), the poses and meshes of its visuals at the movie's frames (at most
    ``max_triangles`` triangles, default :data:`amble.viz.movie.MOVIE_TRIANGLES`; 0: balls and
    sticks), for :func:`amble.viz.movie.write_movie`."""
    from .movie import MOVIE_TRIANGLES, movie_times

    shapes = look_of(traj.system, traj.parameters, look)
    budget = MOVIE_TRIANGLES if max_triangles is None else int(max_triangles)
    if look or budget <= 0:
        return shapes, None
    shapes, poses, meshes, _ = with_meshes(traj, movie_times(traj, path, fps), shapes, budget)
    return shapes, ((poses, meshes) if meshes else None)


def animate(traj: Trajectory, path: str | Path, fps: float = 60.0, look: Sequence[Any] | None = None,
            progress: bool | None = None, series: SeriesSpec = None,
            max_triangles: int | None = None) -> Path:
    """Write an animation of ``traj``: ``.html`` (3D, offline, interactive), ``.gif`` or ``.mp4``.

    ``look``: the shapes to draw (:mod:`amble.viz.scene`); default: made from the model. A movie
    plays in the trajectory's time with a clock, at most 30 fps (a GIF at a rate whose frames last
    whole hundredths of a second: 25 fps for 30); ``progress``: a progress bar while a movie is
    written (default: when stderr is a terminal). See :mod:`amble.viz.movie`. ``series``: state
    variables (and ``"energy"``) plotted under the 3D view of the ``.html`` viewer, with
    labelled axes, a legend and a playhead showing the current values: a list of names (those of
    one unit share a panel) or a mapping panel title → names (see :func:`series_groups`; default:
    the coordinates and the energy; ``[]`` for no panel). A robot read
    from a URDF is drawn with its visual meshes, at most ``max_triangles`` triangles together
    (default: :data:`amble.viz.meshes.MAX_TRIANGLES` in the ``.html`` viewer,
    :data:`amble.viz.movie.MOVIE_TRIANGLES` in a movie; 0: balls and sticks)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".html":
        from .html import write_html

        return write_html(path, scene_of(traj, fps, look, series, max_triangles), title=f"amble — {traj.system.name}")
    if suffix in (".gif", ".mp4"):
        from .movie import check_writer, write_movie

        check_writer(path)
        system = traj.system
        slope = _slope(system, traj.parameters) if isinstance(system, Walker) else None
        shapes, solids = movie_look(traj, path, fps, look, max_triangles)
        return write_movie(traj, path, fps, shapes, slope, progress=progress, solids=solids)
    raise VizError(f"unknown animation format {path.suffix!r}: use .html, .gif or .mp4")
